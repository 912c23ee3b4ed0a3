//! The crate reads top to bottom as the data flows (src/lib.rs): every module may use the ones
//! before it in [`LAYERS`] and none after it. This reads every source file's code (comments
//! left out) for `crate::MODULE` paths and fails naming the file and line of any that runs
//! upwards, so the rule holds as the code grows.

use std::path::Path;

/// Lowest first: foundations, then the stages in the order the data flows, then the
/// experiments built on the renderer.
const LAYERS: &[&str] = &[
    "interrupt",
    "timing",
    "resident_memory",
    "sampling",
    "optics",
    "bsdf",
    "spectrum",
    "image_io",
    "image_metrics",
    "scene",
    "embree",
    "media",
    "world",
    "photon",
    "estimate",
    "render",
    "density",
    "tradeoff",
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file under src/ belongs to (None for lib.rs and main.rs).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).unwrap();
    let first = relative.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (!["lib", "main"].contains(&name)).then(|| name.to_string())
}

/// The `crate::NAME` paths on a line of code, ignoring comments and string literals' contents
/// only as far as a `//` comment goes (no string in src/ spells a crate path).
fn crate_paths(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    let mut found = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let after = &rest[at + "crate::".len()..];
        let name: String = after
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        let grouped = after.starts_with('{');
        if grouped {
            // `use crate::{a, b::c}`: every name at the top of the group.
            let group = &after[1..after.find('}').unwrap_or(after.len())];
            for part in group.split(',') {
                let head: String = part
                    .trim()
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !head.is_empty() {
                    found.push(head);
                }
            }
        } else if !name.is_empty() {
            found.push(name);
        }
        rest = after;
    }
    found
}

#[test]
fn every_import_runs_down_the_data_flow() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let rank = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut upward = Vec::new();
    let mut checked = 0;
    for file in &files {
        let Some(module) = module_of(&src, file) else {
            continue;
        };
        let own = rank(&module)
            .unwrap_or_else(|| panic!("{}: module {module} is not in LAYERS", file.display()));
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            for used in crate_paths(line) {
                let Some(theirs) = rank(&used) else { continue };
                checked += 1;
                if theirs > own {
                    upward.push(format!(
                        "{}:{}: {module} uses {used}",
                        file.display(),
                        n + 1
                    ));
                }
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} crate paths found: is the reader broken?"
    );
    assert!(
        upward.is_empty(),
        "imports running upwards:\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_reader_finds_grouped_and_plain_paths() {
    assert_eq!(crate_paths("use crate::photon::PhotonMap;"), ["photon"]);
    assert_eq!(
        crate_paths("use crate::{estimate::Query, image_io};"),
        ["estimate", "image_io"]
    );
    assert!(crate_paths("// see crate::render").is_empty());
    assert_eq!(
        crate_paths("let x = crate::timing::progress(1, \"a\");"),
        ["timing"]
    );
}
