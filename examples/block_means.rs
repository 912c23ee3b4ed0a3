//! Compares the means of two linear images (.pfm or .exr) of one size, as a check of bias
//! against another renderer's converged image: the whole image's mean over the reference's,
//! each channel's, and the mean of every BLOCK × BLOCK block (the RGB means) over the
//! reference's, with the worst blocks named by their pixel corner. Blocks the reference
//! leaves darker than 1% of its mean are listed apart (their ratios are noise over nothing).
//!
//! `cargo run --release --example block_means -- IMAGE REFERENCE [BLOCK]` (BLOCK defaults to 50)

use dpm::image_io::{Image, read_image};
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (image, reference, block) = match args.as_slice() {
        [a, b] => (a, b, Ok(50)),
        [a, b, n] => (a, b, n.parse::<usize>()),
        _ => {
            eprintln!("usage: block_means IMAGE REFERENCE [BLOCK]");
            return ExitCode::from(2);
        }
    };
    let Ok(block) = block.map(|b| b.max(1)) else {
        eprintln!("error: BLOCK is a whole number of pixels");
        return ExitCode::from(2);
    };
    let (a, b) = match (
        read_image(Path::new(image)),
        read_image(Path::new(reference)),
    ) {
        (Ok(a), Ok(b)) if (a.width, a.height) == (b.width, b.height) => (a, b),
        (Ok(a), Ok(b)) => {
            eprintln!(
                "error: {}x{} against {}x{}",
                a.width, a.height, b.width, b.height
            );
            return ExitCode::from(2);
        }
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let channel_means = |i: &Image| {
        let n = i.pixels.len() as f64;
        let sum = i.pixels.iter().fold([0.0f64; 3], |s, p| {
            [s[0] + p.x as f64, s[1] + p.y as f64, s[2] + p.z as f64]
        });
        sum.map(|c| c / n)
    };
    let (ma, mb) = (channel_means(&a), channel_means(&b));
    let mean = |m: [f64; 3]| (m[0] + m[1] + m[2]) / 3.0;
    println!("image mean / reference mean: {:.4}", mean(ma) / mean(mb));
    println!(
        "channels (r, g, b): {:.4} {:.4} {:.4}",
        ma[0] / mb[0],
        ma[1] / mb[1],
        ma[2] / mb[2]
    );
    let block_mean = |i: &Image, x0: usize, y0: usize| {
        let (mut sum, mut n) = (0.0f64, 0usize);
        for y in y0..(y0 + block).min(i.height) {
            for x in x0..(x0 + block).min(i.width) {
                let p = i.pixels[y * i.width + x];
                sum += (p.x as f64 + p.y as f64 + p.z as f64) / 3.0;
                n += 1;
            }
        }
        sum / n as f64
    };
    let dark = 0.01 * mean(mb);
    let mut ratios = Vec::new();
    let mut dark_blocks = 0;
    for y0 in (0..a.height).step_by(block) {
        for x0 in (0..a.width).step_by(block) {
            let (ea, eb) = (block_mean(&a, x0, y0), block_mean(&b, x0, y0));
            if eb > dark {
                ratios.push((ea / eb, x0, y0));
            } else {
                dark_blocks += 1;
            }
        }
    }
    ratios.sort_by(|p, q| p.0.total_cmp(&q.0));
    let worst = ratios
        .iter()
        .map(|r| (r.0 - 1.0).abs())
        .fold(0.0f64, f64::max);
    println!(
        "{} blocks of {block}x{block}: ratio {:.4} to {:.4}, largest |ratio - 1| {:.4}; {dark_blocks} dark blocks left out",
        ratios.len(),
        ratios.first().map_or(f64::NAN, |r| r.0),
        ratios.last().map_or(f64::NAN, |r| r.0),
        worst
    );
    for (ratio, x, y) in ratios.iter().take(3).chain(ratios.iter().rev().take(3)) {
        println!("  block at ({x}, {y}): {ratio:.4}");
    }
    ExitCode::SUCCESS
}
