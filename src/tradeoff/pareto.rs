//! The Pareto front of (time, error) points: the runs that no other run beats on both time and
//! error. A pure function with no I/O; it must not know what the points measure or where they
//! come from (the sweep, the plot and the table all call it).

/// Indices of the non-dominated points, sorted by time (then error, then index).
///
/// Point `i` is dominated when some point `j` has `time_j ≤ time_i` and `error_j ≤ error_i`
/// with at least one of them strictly smaller. Identical points do not dominate each other, so
/// duplicates on the front are all kept. Points with a non-finite coordinate are left out.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0)
            .then(pa.1.total_cmp(&pb.1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    // The lowest error seen so far and the time of the first (fastest) point that reached it.
    let mut best: Option<(f64, f64)> = None;
    for i in order {
        let (t, e) = points[i];
        let keep = match best {
            None => true,
            Some((best_e, best_t)) => e < best_e || (e == best_e && t == best_t),
        };
        if keep {
            front.push(i);
            if best.is_none_or(|(best_e, _)| e < best_e) {
                best = Some((e, t));
            }
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_lower_left_staircase() {
        let points = [(1.0, 5.0), (2.0, 3.0), (2.5, 4.0), (3.0, 1.0), (0.5, 9.0)];
        assert_eq!(pareto_front(&points), vec![4, 0, 1, 3]);
    }

    #[test]
    fn equal_time_keeps_only_the_lower_error_and_duplicates_stay() {
        let points = [(1.0, 2.0), (1.0, 1.0), (1.0, 1.0), (2.0, 1.0)];
        assert_eq!(pareto_front(&points), vec![1, 2]);
    }

    #[test]
    fn non_finite_points_are_left_out() {
        let points = [(f64::NAN, 0.0), (1.0, f64::INFINITY), (2.0, 2.0)];
        assert_eq!(pareto_front(&points), vec![2]);
        assert!(pareto_front(&[]).is_empty());
    }
}
