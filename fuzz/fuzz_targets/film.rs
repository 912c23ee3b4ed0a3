//! The film loader (`dpm merge` input and `--resume`): a film comes back with finite sums of
//! the size its header names and at least one pass, or an error that names the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;

fn input_path() -> PathBuf {
    std::env::temp_dir().join(format!("dpm-fuzz-film-{}.film", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(&path, data).expect("temp file");
    match dpm::render::film_file::read(&path) {
        Ok(film) => {
            let h = &film.header;
            assert_eq!(film.sums().len(), h.width * h.height * h.channels());
            assert!(film.sums().iter().all(|v| v.is_finite()));
            assert!(!film.passes().is_empty());
        }
        Err(e) => assert!(e.to_string().contains(path.to_str().unwrap()), "{e}"),
    }
});
