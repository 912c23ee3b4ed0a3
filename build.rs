//! Generates the Embree 3 bindings with bindgen and links `embree3`.
//! When the headers or libclang are missing the build stops with one line saying what to install.

use std::env;
use std::path::{Path, PathBuf};

const INSTALL_HINT: &str = "apt-get install -y libembree-dev libclang-dev";

fn stop(message: &str) -> ! {
    eprintln!("error: {message}; install them with `{INSTALL_HINT}`");
    std::process::exit(1);
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=EMBREE_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=EMBREE_LIB_DIR");
    let include = env::var_os("EMBREE_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/include"));
    let header = include.join("embree3/rtcore.h");
    if !header.is_file() {
        stop(&format!(
            "Embree 3 headers not found ({})",
            header.display()
        ));
    }
    println!("cargo:rerun-if-changed={}", header.display());
    if let Some(lib) = env::var_os("EMBREE_LIB_DIR") {
        println!(
            "cargo:rustc-link-search=native={}",
            Path::new(&lib).display()
        );
    }
    println!("cargo:rustc-link-lib=dylib=embree3");

    // bindgen panics when it cannot load libclang; turn that into the one-line message.
    std::panic::set_hook(Box::new(|_| {}));
    let generated = std::panic::catch_unwind(|| {
        bindgen::Builder::default()
            .header(header.to_string_lossy())
            .clang_arg(format!("-I{}", include.display()))
            .allowlist_function("rtc.*")
            .allowlist_type("RTC.*")
            .allowlist_var("RTC_.*")
            .prepend_enum_name(false)
            .derive_default(true)
            .layout_tests(false)
            .generate()
    });
    let _ = std::panic::take_hook();
    let bindings = match generated {
        Ok(Ok(b)) => b,
        Ok(Err(e)) => stop(&format!("bindgen could not read the Embree headers ({e})")),
        Err(_) => stop("bindgen could not load libclang"),
    };
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    if let Err(e) = bindings.write_to_file(out.join("embree3.rs")) {
        stop(&format!("could not write the Embree bindings ({e})"));
    }
}
