//! The documentation holds together: every relative link in `README.md` and
//! `docs/**/*.md` names a file that exists (and, for `#anchor` links into
//! Markdown, a heading that exists, by GitHub's slug rules); the README stays
//! a short user document (at most 600 lines); and no text file of the tree
//! dates anything by numbered work rounds: the word for such a round followed
//! by a space and a digit (what `grep -rniE` would find with that pattern)
//! appears nowhere. The docs describe the software, and figures are dated by
//! the commit they were measured at.
//!
//! Standard library only. The root is `CARGO_MANIFEST_DIR` at build time, or
//! the current directory when built without cargo:
//! `rustc --edition 2024 --test tests/suite/docs.rs -o /tmp/docs_test && /tmp/docs_test`
//! from the repository root.

use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};

const README_MAX_LINES: usize = 600;

fn root() -> PathBuf {
    match option_env!("CARGO_MANIFEST_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => std::env::current_dir().expect("current directory"),
    }
}

/// `README.md` and every Markdown file under `docs/`.
fn markdown_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![root.join("README.md")];
    let mut dirs = vec![root.join("docs")];
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let Ok(kind) = entry.file_type() else {
                continue;
            };
            if kind.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The lines of a Markdown text outside fenced code blocks.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut in_fence = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            in_fence = !in_fence;
            continue;
        }
        if !in_fence {
            lines.push(line);
        }
    }
    lines
}

/// A line with its inline code spans (`...`) removed.
fn without_code_spans(line: &str) -> String {
    let mut out = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
        } else if !in_code {
            out.push(c);
        }
    }
    out
}

/// GitHub's anchor for a heading: lower case, inline code and punctuation
/// dropped except `-` and `_`, each space a `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            c if c.is_alphanumeric() => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown file's headings; a repeated heading gets `-1`,
/// `-2`, ... as on GitHub.
fn anchors(text: &str) -> HashSet<String> {
    let mut seen = HashSet::new();
    for line in prose_lines(text) {
        let trimmed = line.trim_start();
        let hashes = trimmed.chars().take_while(|&c| c == '#').count();
        if hashes == 0 || hashes > 6 || !trimmed[hashes..].starts_with(' ') {
            continue;
        }
        let base = slug(&trimmed[hashes..]);
        let mut anchor = base.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

/// The targets of the inline links and images, `[text](target)`, of a
/// Markdown text, with their line numbers.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut targets = Vec::new();
    let mut in_fence = false;
    for (number, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let line = without_code_spans(line);
        let mut rest = line.as_str();
        while let Some(start) = rest.find("](") {
            let after = &rest[start + 2..];
            let Some(end) = after.find(')') else { break };
            let target = after[..end].split_whitespace().next().unwrap_or("");
            let target = target.trim_start_matches('<').trim_end_matches('>');
            targets.push((number + 1, target.to_string()));
            rest = &after[end..];
        }
    }
    targets
}

/// Every broken relative link of the Markdown files under `root`, one line
/// each.
fn broken_links(root: &Path) -> Vec<String> {
    let mut broken = Vec::new();
    for file in markdown_files(root) {
        let Ok(text) = fs::read_to_string(&file) else {
            broken.push(format!("{}: cannot be read", file.display()));
            continue;
        };
        let dir = file.parent().expect("a file has a folder");
        for (line, target) in link_targets(&text) {
            if target.is_empty()
                || target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((path, anchor)) => (path, Some(anchor)),
                None => (target.as_str(), None),
            };
            let linked = if path.is_empty() {
                file.clone()
            } else {
                dir.join(path)
            };
            let place = format!("{}:{line}: ({target})", file.display());
            if !linked.exists() {
                broken.push(format!("{place} names no file"));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            if linked.extension().is_none_or(|e| e != "md") {
                continue;
            }
            let linked_text = fs::read_to_string(&linked).unwrap_or_default();
            if !anchors(&linked_text).contains(anchor) {
                broken.push(format!("{place} names no heading of {}", linked.display()));
            }
        }
    }
    broken
}

/// Whether `line` holds the round-numbering pattern: the word, one space,
/// a digit, in any case.
fn dates_by_round(line: &str) -> bool {
    let word = ['s', 'e', 's', 's', 'i', 'o', 'n']
        .iter()
        .collect::<String>();
    let lower = line.to_lowercase();
    let bytes = lower.as_bytes();
    let mut from = 0;
    while let Some(at) = lower[from..].find(&word) {
        let end = from + at + word.len();
        if bytes.get(end) == Some(&b' ') && bytes.get(end + 1).is_some_and(u8::is_ascii_digit) {
            return true;
        }
        from = end;
    }
    false
}

/// Every line of the tree's text files (outside `target/` and `.git`) that
/// dates by numbered rounds, as `path:line: text`.
fn round_numbered_lines(root: &Path) -> Vec<String> {
    let mut found = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name();
            if name == ".git" || name == "target" {
                continue;
            }
            let Ok(kind) = entry.file_type() else {
                continue;
            };
            if kind.is_dir() {
                dirs.push(path);
                continue;
            }
            if !kind.is_file() {
                continue;
            }
            let Ok(bytes) = fs::read(&path) else { continue };
            if bytes.iter().take(8192).any(|&b| b == 0) {
                continue; // binary
            }
            let Ok(text) = String::from_utf8(bytes) else {
                continue;
            };
            for (number, line) in text.lines().enumerate() {
                if dates_by_round(line) {
                    let shown: String = line.trim().chars().take(100).collect();
                    found.push(format!("{}:{}: {shown}", path.display(), number + 1));
                }
            }
        }
    }
    found.sort();
    found
}

#[test]
fn every_relative_link_in_the_docs_resolves() {
    let broken = broken_links(&root());
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn nothing_is_dated_by_numbered_work_rounds() {
    let found = round_numbered_lines(&root());
    assert!(
        found.is_empty(),
        "date these by commit instead (git log), or describe the software:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_readme_is_short() {
    let text = fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = text.lines().count();
    assert!(
        lines <= README_MAX_LINES,
        "README.md has {lines} lines, at most {README_MAX_LINES}: move detail into docs/"
    );
}

#[test]
fn slugs_follow_githubs_rules() {
    assert_eq!(
        slug("Set up (Debian 12 / Ubuntu, Rust 1.89+)"),
        "set-up-debian-12--ubuntu-rust-189"
    );
    assert_eq!(
        slug("How fast and how accurate"),
        "how-fast-and-how-accurate"
    );
    assert_eq!(
        slug("`vkpt compare`: two renders"),
        "vkpt-compare-two-renders"
    );
    let text = "# A\n```\n# not a heading\n```\n## A\n";
    let found = anchors(text);
    assert!(found.contains("a") && found.contains("a-1") && !found.contains("not-a-heading"));
}

#[test]
fn the_round_pattern_is_found_in_any_case_and_only_before_a_digit() {
    let word = ['S', 'e', 's', 's', 'i', 'o', 'n']
        .iter()
        .collect::<String>();
    assert!(dates_by_round(&format!("as {word} 3 found")));
    assert!(dates_by_round(&format!("({} 12)", word.to_uppercase())));
    assert!(!dates_by_round(&format!("a {word} of work")));
    assert!(!dates_by_round(&format!("{word}s 3")));
}
