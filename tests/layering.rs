//! The library's folders are layers, and imports only point down: a module
//! may name (`crate::x`) only its own layer and the layers listed before it
//! in `LAYERS`. `cache` and `constants` are leaves every layer may read. The
//! command line (`src/bin/`, `src/main.rs`) sits above all of them and uses
//! the library only through `vkpt::`.
//!
//! The check reads the source text: every `crate::name` in `src/` (code and
//! doc links alike, so a doc comment pointing up fails too).

use std::path::{Path, PathBuf};

/// Bottom to top.
const LAYERS: &[&str] = &[
    "image", "scene", "packed", "film", "cpu", "gpu", "render", "bench",
];
const LEAVES: &[&str] = &["cache", "constants"];
/// Layers that must not name each other although neither is above the other.
const SIBLINGS: &[(&str, &str)] = &[("cpu", "gpu")];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir)
        .expect("readable src folder")
        .flatten()
    {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The layer a file under `src/` belongs to: its first path component.
fn layer_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src");
    let first = rel.components().next().expect("non-empty path");
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_string()
}

/// Every `crate::name` in `text`.
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            let before = rest[..i].chars().last();
            let after = &rest[i + "crate::".len()..];
            rest = after;
            // `vkpt_crate::` or `my_crate::` are not this crate.
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let name: String = after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                found.push((line_no + 1, name));
            }
        }
    }
    found
}

fn rank(layer: &str) -> Option<usize> {
    LAYERS.iter().position(|l| *l == layer)
}

#[test]
fn imports_between_layers_point_down() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut checked = 0;
    for file in &files {
        let layer = layer_of(&src, file);
        if layer == "lib" || layer == "main" || layer == "bin" {
            continue;
        }
        let text = std::fs::read_to_string(file).expect("readable source");
        let own = rank(&layer);
        for (line, target) in crate_paths(&text) {
            checked += 1;
            if target == layer || LEAVES.contains(&target.as_str()) {
                continue;
            }
            let shown = file.strip_prefix(&src).unwrap_or(file).display();
            if LEAVES.contains(&layer.as_str()) {
                violations.push(format!(
                    "src/{shown}:{line}: leaf `{layer}` names crate::{target}"
                ));
                continue;
            }
            let (Some(own), Some(other)) = (own, rank(&target)) else {
                violations.push(format!(
                    "src/{shown}:{line}: crate::{target} from `{layer}`: not a known layer \
                     (add it to LAYERS in tests/layering.rs)"
                ));
                continue;
            };
            let sibling = SIBLINGS
                .iter()
                .any(|&(a, b)| (a == layer && b == target) || (b == layer && a == target));
            if other > own || sibling {
                violations.push(format!(
                    "src/{shown}:{line}: `{layer}` names crate::{target}, which is not below it"
                ));
            }
        }
    }
    println!("{checked} crate:: paths in {} files checked", files.len());
    assert!(
        checked > 100,
        "the check found almost no imports: is it reading src/?"
    );
    assert!(
        violations.is_empty(),
        "imports that point up or sideways:\n{}",
        violations.join("\n")
    );
}

#[test]
fn every_top_level_module_is_a_known_layer_or_leaf() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("src/lib.rs");
    for line in lib.lines() {
        let Some(name) = line.trim().strip_prefix("pub mod ") else {
            continue;
        };
        let name = name.trim_end_matches(';');
        assert!(
            rank(name).is_some() || LEAVES.contains(&name),
            "src/lib.rs declares `{name}`, which tests/layering.rs does not place in a layer"
        );
    }
}

#[test]
fn the_check_sees_an_upward_import() {
    // The scanner itself: a planted upward path is found, `my_crate::` is not.
    let paths = crate_paths("use crate::render::x; // see my_crate::gpu\n  crate::cpu::y");
    let names: Vec<&str> = paths.iter().map(|(_, n)| n.as_str()).collect();
    assert_eq!(names, ["render", "cpu"]);
}
