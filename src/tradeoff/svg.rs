//! The error-against-time plot as SVG text, written by hand: a log-scale time axis, a linear
//! error axis, one colour and marker per series, each series' Pareto front as a line, axis
//! labels and a legend. Owns layout and SVG syntax only; it must not compute fronts (the
//! caller passes them) or write files.

use std::fmt::Write as _;

/// One estimate's points (seconds, error) and the indices of its front, in time order.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub front: Vec<usize>,
}

const WIDTH: f64 = 760.0;
const HEIGHT: f64 = 480.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 190.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;
const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf",
];

/// Escapes text for SVG content and attribute values.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A marker shape per series index, centred on (x, y).
fn marker(index: usize, x: f64, y: f64, colour: &str) -> String {
    let s = 4.5;
    match index % 4 {
        0 => format!(r#"<circle cx="{x:.1}" cy="{y:.1}" r="{s}" fill="{colour}"/>"#),
        1 => format!(
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}"/>"#,
            x - s,
            y - s,
            2.0 * s,
            2.0 * s
        ),
        2 => format!(
            r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{colour}"/>"#,
            x,
            y - 1.2 * s,
            x - 1.1 * s,
            y + 0.9 * s,
            x + 1.1 * s,
            y + 0.9 * s
        ),
        _ => format!(
            r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{colour}"/>"#,
            x,
            y - 1.3 * s,
            x + 1.3 * s,
            y,
            x,
            y + 1.3 * s,
            x - 1.3 * s,
            y
        ),
    }
}

/// "Nice" linear ticks covering [lo, hi]: steps of 1, 2 or 5 × 10ⁿ, about five of them.
fn linear_ticks(lo: f64, hi: f64) -> (f64, f64, Vec<f64>) {
    let span = (hi - lo).max(hi.abs() * 1e-6).max(1e-300);
    let raw = span / 5.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude);
    let (lo, hi) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    let n = ((hi - lo) / step).round() as usize;
    (lo, hi, (0..=n).map(|i| lo + i as f64 * step).collect())
}

/// Ticks on a log axis: 1, 2 and 5 × each decade within [lo, hi] (lo > 0).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let t = m * decade;
            if t >= lo * 0.999 && t <= hi * 1.001 {
                ticks.push(t);
            }
        }
        decade *= 10.0;
    }
    ticks
}

fn tick_label(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1000.0 || v.abs() < 0.001 {
        format!("{v:.0e}")
    } else {
        let text = format!("{v:.4}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The plot as an SVG document. Points with a non-finite value or a time ≤ 0 are left out.
pub fn plot(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let usable = |&(t, e): &(f64, f64)| t > 0.0 && t.is_finite() && e.is_finite();
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied().filter(usable))
        .collect();
    let (t_min, t_max) = all.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (e_min, e_max) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    let (t_lo, t_hi) = if all.is_empty() {
        (0.1, 10.0)
    } else {
        (t_min / 1.25, t_max * 1.25)
    };
    let (e_lo, e_hi, y_ticks) = if all.is_empty() {
        linear_ticks(0.0, 1.0)
    } else {
        linear_ticks(
            e_min - 0.05 * (e_max - e_min),
            e_max + 0.05 * (e_max - e_min),
        )
    };
    let (plot_w, plot_h) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
    let x_of = |t: f64| LEFT + (t.ln() - t_lo.ln()) / (t_hi.ln() - t_lo.ln()) * plot_w;
    let y_of = |e: f64| TOP + (e_hi - e) / (e_hi - e_lo).max(1e-300) * plot_h;

    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(
        svg,
        r#"<rect width="{WIDTH}" height="{HEIGHT}" fill="white"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
        LEFT + plot_w / 2.0,
        escape(title)
    );
    // Grid and tick labels.
    svg.push_str("<g class=\"axes\" stroke=\"#ddd\">\n");
    for t in log_ticks(t_lo, t_hi) {
        let x = x_of(t);
        let _ = writeln!(
            svg,
            r#"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" stroke="none" fill="black">{}</text>"#,
            TOP + plot_h,
            TOP + plot_h + 16.0,
            tick_label(t)
        );
    }
    for e in &y_ticks {
        let y = y_of(*e);
        let _ = writeln!(
            svg,
            r#"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}"/><text x="{:.1}" y="{:.1}" text-anchor="end" stroke="none" fill="black">{}</text>"#,
            LEFT + plot_w,
            LEFT - 6.0,
            y + 4.0,
            tick_label(*e)
        );
    }
    svg.push_str("</g>\n");
    let _ = writeln!(
        svg,
        r#"<rect x="{LEFT}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        LEFT + plot_w / 2.0,
        HEIGHT - 16.0,
        escape(x_label)
    );
    let _ = writeln!(
        svg,
        r#"<text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">{}</text>"#,
        TOP + plot_h / 2.0,
        TOP + plot_h / 2.0,
        escape(y_label)
    );

    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let name = escape(&s.name);
        let _ = writeln!(svg, r#"<g class="series" data-estimate="{name}">"#);
        let front: Vec<String> = s
            .front
            .iter()
            .map(|&j| s.points[j])
            .filter(usable)
            .map(|(t, e)| format!("{:.1},{:.1}", x_of(t), y_of(e)))
            .collect();
        let _ = writeln!(
            svg,
            r#"<polyline class="front" data-estimate="{name}" points="{}" fill="none" stroke="{colour}" stroke-width="1.8"/>"#,
            front.join(" ")
        );
        for &(t, e) in s.points.iter().filter(|p| usable(p)) {
            let _ = writeln!(svg, "{}", marker(i, x_of(t), y_of(e), colour));
        }
        svg.push_str("</g>\n");
        // Legend entry.
        let (lx, ly) = (LEFT + plot_w + 20.0, TOP + 16.0 + 22.0 * i as f64);
        let _ = writeln!(
            svg,
            r#"<g class="legend"><line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="1.8"/>{}<text x="{:.1}" y="{:.1}">{name}</text></g>"#,
            lx + 28.0,
            marker(i, lx + 14.0, ly, colour),
            lx + 36.0,
            ly + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r##"<text x="{:.1}" y="{:.1}" font-size="11" fill="#555">lines: Pareto fronts</text>"##,
        LEFT + plot_w + 20.0,
        TOP + 16.0 + 22.0 * series.len() as f64 + 6.0
    );
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_their_range() {
        let (lo, hi, ticks) = linear_ticks(0.13, 0.87);
        assert!(lo <= 0.13 && hi >= 0.87 && ticks.len() >= 3 && ticks.len() <= 12);
        assert_eq!(log_ticks(0.3, 30.0), vec![0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
    }
}
