//! Builds dpm's door to Embree, on one of two backends:
//! - default: Debian 12's Embree 3 (`libembree-dev`): bindgen generates the bindings from
//!   `/usr/include/embree3` (or `$EMBREE_INCLUDE_DIR`) and `embree3` is linked;
//! - feature `embree4`: the `embree4-sys` crate's bindings (Embree 4.2.0 headers), linked with
//!   the Embree 4.4.0 libraries that `scripts/fetch-embree4.sh` puts in `$EMBREE4_DIR` (default
//!   `target/embree4`), with an rpath to that folder so the binaries run without
//!   `LD_LIBRARY_PATH`.
//!
//! Either way `cc` compiles the backend's C shim (`src/embree/shim3.c` or `shim4.c`) against the
//! same headers, so Embree's header-inline functions and the argument structs they fill are laid
//! out by the C compiler, never re-typed in Rust. When something is missing the build stops with
//! one line saying what to install or run.

use std::env;
use std::path::{Path, PathBuf};

const INSTALL_HINT: &str = "apt-get install -y libembree-dev libclang-dev";
/// The `embree4-sys` release whose headers the Embree 4 shim is compiled against; Cargo.toml
/// pins the same version.
const EMBREE4_SYS: &str = "embree4-sys-0.0.12";

fn stop(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var_os("CARGO_FEATURE_EMBREE4").is_some() {
        embree4();
    } else {
        embree3();
    }
}

fn embree3() {
    println!("cargo:rerun-if-env-changed=EMBREE_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=EMBREE_LIB_DIR");
    let include = env::var_os("EMBREE_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/include"));
    let header = include.join("embree3/rtcore.h");
    if !header.is_file() {
        stop(&format!(
            "Embree 3 headers not found ({}); install them with `{INSTALL_HINT}`",
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
    shim("src/embree/shim3.c", &include);

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
        Ok(Err(e)) => stop(&format!(
            "bindgen could not read the Embree headers ({e}); install them with `{INSTALL_HINT}`"
        )),
        Err(_) => stop(&format!(
            "bindgen could not load libclang; install it with `{INSTALL_HINT}`"
        )),
    };
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    if let Err(e) = bindings.write_to_file(out.join("embree3.rs")) {
        stop(&format!("could not write the Embree bindings ({e})"));
    }
}

fn embree4() {
    println!("cargo:rerun-if-env-changed=EMBREE4_DIR");
    println!("cargo:rerun-if-env-changed=EMBREE4_INCLUDE_DIR");
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let dir = env::var_os("EMBREE4_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| manifest.join("target/embree4"));
    let library = dir.join("libembree4.so");
    if !library.exists() {
        stop(&format!(
            "Embree 4 not found ({}); fetch it with `scripts/fetch-embree4.sh`",
            library.display()
        ));
    }
    println!("cargo:rerun-if-changed={}", library.display());
    let dir = dir.canonicalize().unwrap_or(dir);
    // `embree4-sys` asks for `embree4`; this says where it is, and where to find it at run time.
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    shim("src/embree/shim4.c", &embree4_headers());
}

/// The folder holding `embree4/rtcore.h`: `$EMBREE4_INCLUDE_DIR`, else the headers shipped in
/// the `embree4-sys` crate's source (its `lib/` folder). That crate declares no `links` key, so
/// it exports no `DEP_*` metadata; its source is found in Cargo's registry instead
/// (`$CARGO_HOME/registry/src/*/embree4-sys-0.0.12/lib`).
fn embree4_headers() -> PathBuf {
    if let Some(dir) = env::var_os("EMBREE4_INCLUDE_DIR") {
        return PathBuf::from(dir);
    }
    let cargo_home = env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
        .unwrap_or_else(|| PathBuf::from(".cargo"));
    let registry = cargo_home.join("registry/src");
    let found = std::fs::read_dir(&registry).ok().and_then(|indexes| {
        indexes
            .flatten()
            .map(|index| index.path().join(EMBREE4_SYS).join("lib"))
            .find(|lib| lib.join("embree4/rtcore.h").is_file())
    });
    found.unwrap_or_else(|| {
        stop(&format!(
            "the {EMBREE4_SYS} headers were not found under {}; set EMBREE4_INCLUDE_DIR to the \
             folder holding embree4/rtcore.h",
            registry.display()
        ))
    })
}

/// Compiles the backend's C shim against the headers in `include`.
fn shim(source: &str, include: &Path) {
    println!("cargo:rerun-if-changed={source}");
    println!("cargo:rerun-if-changed=src/embree/shim_common.h");
    cc::Build::new()
        .file(source)
        .include(include)
        .opt_level(2)
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true)
        .compile("dpm_embree_shim");
}
