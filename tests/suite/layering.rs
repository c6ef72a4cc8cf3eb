//! The library's folders are layers, and imports only point down: a module
//! may name (`crate::x`) only its own layer and the layers listed before it
//! in `LAYERS`. `cache`, `constants`, `huge_pages` and `splitmix` are leaves every layer
//! may read. The
//! command line (`src/bin/`, `src/main.rs`) sits above all of them and uses
//! the library only through `vkpt::`.
//!
//! The check reads the source text: every `crate::name` in `src/` (code and
//! doc links alike, so a doc comment pointing up fails too).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Bottom to top.
const LAYERS: &[&str] = &[
    "image", "scene", "packed", "film", "cpu", "gpu", "render", "bench",
];
const LEAVES: &[&str] = &["cache", "constants", "huge_pages", "splitmix"];
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
                     (add it to LAYERS in tests/suite/layering.rs)"
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
            "src/lib.rs declares `{name}`, which tests/suite/layering.rs does not place in a layer"
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

/// The CPU back end's modules (`src/cpu/**.rs`, tests excluded) as paths
/// below `cpu` (`common::bvh`, `fast::cache::node_planes`, `traversal`),
/// with the modules each one names: `crate::cpu::…` paths, and `super::…`
/// paths resolved from the file's place. Text after a file's unit-test
/// module (`mod tests`) is left out: tests may name what they test.
fn cpu_imports(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let cpu = src.join("cpu");
    let mut files = Vec::new();
    rust_files(&cpu, &mut files);
    let module_of = |file: &Path| -> Vec<String> {
        let rel = file.strip_prefix(&cpu).expect("under src/cpu");
        let mut parts: Vec<String> = rel
            .components()
            .map(|c| {
                c.as_os_str()
                    .to_string_lossy()
                    .trim_end_matches(".rs")
                    .to_string()
            })
            .collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        parts
    };
    let modules: BTreeSet<String> = files
        .iter()
        .filter(|f| !f.components().any(|c| c.as_os_str() == "tests"))
        .map(|f| module_of(f).join("::"))
        .collect();
    // The longest known module a path starts with.
    let known = |path: &[String]| -> Option<String> {
        (1..=path.len())
            .rev()
            .map(|n| path[..n].join("::"))
            .find(|m| modules.contains(m))
    };
    let mut graph = BTreeMap::new();
    for file in &files {
        if file.components().any(|c| c.as_os_str() == "tests") {
            continue;
        }
        let own = module_of(file);
        let text = std::fs::read_to_string(file).expect("readable source");
        let code = text.split("\nmod tests").next().unwrap_or("");
        let mut names = BTreeSet::new();
        for line in code.lines() {
            let ident = |s: &str| -> Vec<String> {
                s.split("::")
                    .map(|p| {
                        p.chars()
                            .take_while(|c| c.is_alphanumeric() || *c == '_')
                            .collect::<String>()
                    })
                    .take_while(|p| !p.is_empty())
                    .collect()
            };
            for (i, _) in line.match_indices("crate::cpu::") {
                if let Some(m) = known(&ident(&line[i + "crate::cpu::".len()..])) {
                    names.insert(m);
                }
            }
            for (i, _) in line.match_indices("super::") {
                if line[..i].ends_with("super::") {
                    continue;
                }
                // Each `super` is one module up from the file's own.
                let mut rest = &line[i..];
                let mut base = own.clone();
                while let Some(r) = rest.strip_prefix("super::") {
                    rest = r;
                    base.pop();
                }
                let mut path = base;
                path.extend(ident(rest));
                if let Some(m) = known(&path) {
                    names.insert(m);
                }
            }
        }
        let own = own.join("::");
        names.remove(&own);
        graph.insert(own, names);
    }
    graph
}

/// A circle in `graph`, if any, as the modules along it.
fn circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(m) {
            Some(2) => return None,
            Some(1) => {
                let start = path.iter().position(|p| p == m).expect("on the path");
                let mut c = path[start..].to_vec();
                c.push(m.to_string());
                return Some(c);
            }
            _ => {}
        }
        state.insert(m.to_string(), 1);
        path.push(m.to_string());
        for next in graph.get(m).into_iter().flatten() {
            if let Some(c) = visit(next, graph, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    graph
        .keys()
        .find_map(|m| visit(m, graph, &mut state, &mut Vec::new()))
}

/// Inside the CPU back end imports form no circle, and point down its
/// folders: the kernels' twins (`cpu::common`) name nothing of the fast
/// code, the traversal choice or the driver, and the fast code
/// (`cpu::fast`) does not name the driver (`cpu::render`).
#[test]
fn cpu_back_end_imports_point_down_without_a_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = cpu_imports(&src);
    let edges: usize = graph.values().map(|n| n.len()).sum();
    println!("{} CPU modules, {edges} imports between them", graph.len());
    assert!(
        graph.contains_key("common::bvh") && graph.contains_key("fast::lanes") && edges > 50,
        "the check found too little: is it reading src/cpu?"
    );
    if let Some(c) = circle(&graph) {
        panic!(
            "the CPU back end's imports form a circle: {}",
            c.join(" -> ")
        );
    }
    let mut upward = Vec::new();
    for (module, names) in &graph {
        for name in names {
            let up = (module.starts_with("common") && !name.starts_with("common"))
                || (module.starts_with("fast") && name.starts_with("render"));
            if up {
                upward.push(format!("cpu::{module} names cpu::{name}"));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports that point up:\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_cpu_check_sees_a_circle() {
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec![]),
    ]
    .into_iter()
    .map(|(m, n)| (m.to_string(), n.into_iter().map(String::from).collect()))
    .collect();
    assert_eq!(
        circle(&graph).expect("a circle"),
        ["a", "b", "c", "a"].map(String::from)
    );
}

/// Each twin in `src/cpu/common/` is named after its GLSL file.
#[test]
fn every_cpu_twin_has_its_glsl_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src/cpu/common"), &mut files);
    let mut twins = 0;
    for file in files {
        let name = file.file_stem().expect("a file name").to_string_lossy();
        if name == "mod" || file.components().any(|c| c.as_os_str() == "tests") {
            continue;
        }
        let glsl = root.join(format!("shaders/common/{name}.glsl"));
        assert!(
            glsl.exists(),
            "{} has no twin {}",
            file.display(),
            glsl.display()
        );
        twins += 1;
    }
    assert!(
        twins > 10,
        "only {twins} twins found: is it reading src/cpu/common?"
    );
}
