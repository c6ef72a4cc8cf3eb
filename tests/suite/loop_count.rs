//! Every loop the per-path loop kernel can reach counts its iterations
//! (`shaders/common/loop_count.glsl`): lavapipe ends a SIMD group's loops
//! silently after 65,535 iterations in all, and `path_loop.comp` keeps within
//! that by the count. A loop without `COUNT_LOOP_ITERATION();` as the first
//! statement of its body would let a path end early, unseen.

use std::path::Path;

/// (file, line number, loop header) of every `for`, `while` and `do` loop
/// in the GLSL files under `dir` whose body does not start with the count.
fn uncounted_loops(dir: &Path) -> Vec<(String, usize, String)> {
    let mut missing = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("shader folder")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "glsl" || e == "comp"))
        .collect();
    files.sort();
    for path in files {
        let text = std::fs::read_to_string(&path).expect("shader readable");
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let code = line.split("//").next().unwrap_or("").trim();
            let is_loop = ["for (", "for(", "while (", "while(", "do {", "do{"]
                .iter()
                .any(|k| code.starts_with(k) || code.contains(&format!("}} {k}")));
            // `} while (...);` closes a do loop: counted at its `do`.
            if !is_loop || code.starts_with("} while") {
                continue;
            }
            let counted = code.ends_with('{')
                && lines
                    .get(i + 1)
                    .is_some_and(|next| next.trim() == "COUNT_LOOP_ITERATION();");
            if !counted {
                missing.push((path.display().to_string(), i + 1, code.to_string()));
            }
        }
    }
    missing
}

#[test]
fn every_loop_a_bounce_can_reach_counts_its_iterations() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut missing = uncounted_loops(&root.join("common"));
    missing.extend(uncounted_loops(&root.join("path_loop")));
    for (file, line, code) in &missing {
        println!("{file}:{line}: {code}");
    }
    assert!(
        missing.is_empty(),
        "{} loops do not start with COUNT_LOOP_ITERATION(); (listed above)",
        missing.len()
    );
}

#[test]
fn the_check_sees_an_uncounted_loop() {
    let dir = std::env::temp_dir().join(format!("vkpt-loop-count-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(
        dir.join("a.glsl"),
        "void f() {\n    for (uint i = 0u; i < 3u; i++) {\n        COUNT_LOOP_ITERATION();\n    }\n    \
         while (x) {\n        y();\n    }\n}\n",
    )
    .expect("write");
    let missing = uncounted_loops(&dir);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(missing.len(), 1, "{missing:?}");
    assert_eq!(missing[0].1, 5);
}
