//! The error `dpm render --reference` reports, for images made elsewhere (an older dpm, another
//! renderer): relative MSE of IMAGE against REFERENCE, the mean over pixels of (e − r)²/(r² + ε²)
//! of the RGB channel means, ε = 10% of the reference's mean (`dpm::image_metrics::image_relative_mse`).
//!
//! `cargo run --release --example image_error -- IMAGE.pfm|.exr REFERENCE.pfm|.exr`

use dpm::image_io::read_image;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [image, reference] = args.as_slice() else {
        eprintln!("usage: image_error IMAGE REFERENCE");
        return ExitCode::from(2);
    };
    match (
        read_image(Path::new(image)),
        read_image(Path::new(reference)),
    ) {
        (Ok(a), Ok(b)) if (a.width, a.height) == (b.width, b.height) => {
            println!("{:.6e}", dpm::image_metrics::image_relative_mse(&a, &b));
            ExitCode::SUCCESS
        }
        (Ok(a), Ok(b)) => {
            eprintln!(
                "error: {}x{} against {}x{}",
                a.width, a.height, b.width, b.height
            );
            ExitCode::from(2)
        }
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
