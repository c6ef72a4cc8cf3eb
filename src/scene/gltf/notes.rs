//! Wording for the notes and errors the loader hands the user: a note per
//! kind of thing, listing what it applies to, rather than one note per
//! element; elements named by index and name.

use std::collections::BTreeMap;

/// Notes that are gathered per subject and emitted once, listing the subjects.
#[derive(Default)]
pub(super) struct Grouped(pub BTreeMap<String, Vec<String>>);

impl Grouped {
    pub fn add(&mut self, key: impl Into<String>, subject: impl Into<String>) {
        let v = self.0.entry(key.into()).or_default();
        let s = subject.into();
        if !v.contains(&s) {
            v.push(s);
        }
    }
}

/// `'a', 'b', 'c' and 4 more`.
pub(super) fn list(items: &[String]) -> String {
    const MAX: usize = 5;
    let shown = items
        .iter()
        .take(MAX)
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ");
    if items.len() > MAX {
        format!("{shown} and {} more", items.len() - MAX)
    } else {
        shown
    }
}

pub(super) fn plural(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {many}")
    }
}

/// `" 'name'"` for an element that has a name, else empty: messages say
/// `material #2 'glass'` or `material #2`.
pub(super) fn name_suffix(name: Option<&str>) -> String {
    match name {
        Some(n) => format!(" '{n}'"),
        None => String::new(),
    }
}
