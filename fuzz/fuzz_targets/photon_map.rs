//! The photon-map loader (`--load-photons`): maps come back with finite photons, or an error
//! that names the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;

fn input_path() -> PathBuf {
    std::env::temp_dir().join(format!("dpm-fuzz-photons-{}.dpm", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(&path, data).expect("temp file");
    match dpm::photon::store::read(&path) {
        Ok(file) => {
            for stored in &file.maps {
                assert!(
                    stored
                        .map
                        .photons()
                        .all(|p| p.position().is_finite() && p.power().is_finite())
                );
            }
        }
        Err(e) => assert!(e.to_string().contains(path.to_str().unwrap()), "{e}"),
    }
});
