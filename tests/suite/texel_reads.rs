//! Kernels never index the scene structs: they read them as 16-byte texels
//! and pick the fields by hand (`t3.y` is `MaterialData::metallic`). A wrong
//! pick renders a plausible, wrong image that `tests/suite/layout.rs` (which checks
//! the struct declarations) cannot see. So the fetch code follows one
//! convention, and this test checks every texel read against the Rust
//! structs' `offset_of!`:
//!
//! - a struct array is read through a texel view of the binding table whose
//!   viewed buffer holds that struct (`packed::bindings`), by `texelFetch`
//!   or, for a split view, by `scene_texel` (the generated `bindings.glsl`);
//! - its texel index is `stride * i + k`: the stride must be the struct's
//!   size in texels (`3u`, `MATERIAL_TEXELS`), `k` the texel of the field;
//! - each swizzle of such a texel goes into a variable, field or out
//!   parameter named after the struct field it holds (`uint e_imask = n0.w;`,
//!   `d.metallic = uintBitsToFloat(t3.y);`), or is returned by a function
//!   whose name ends with the field's (`fetch_light_pmf`); the swizzle's
//!   first component and length must be the field's offset and size.
//!
//! A texel read that follows none of this fails the test too, so new fetch
//! code cannot go unchecked.

use crate::struct_layouts;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use struct_layouts::{Expected, rust_layouts};
use vkpt::packed::bindings::{BINDINGS, Kind, row_of};

/// Names a texel index may be scaled by, with their values.
const STRIDE_CONSTANTS: &[(&str, u32)] = &[
    ("MATERIAL_TEXELS", vkpt::constants::MATERIAL_TEXELS),
    ("INSTANCE_TEXELS", vkpt::constants::INSTANCE_TEXELS),
];

struct Struct {
    name: &'static str,
    texels: u32,
    /// Field name to (byte offset, size in bytes).
    fields: HashMap<&'static str, (usize, usize)>,
}

impl Struct {
    /// Fields are packed with explicit padding, so a field ends where the
    /// next begins.
    fn new(e: &Expected) -> Struct {
        let mut fields = HashMap::new();
        for (k, &(name, offset)) in e.fields.iter().enumerate() {
            let end = e.fields.get(k + 1).map_or(e.size, |f| f.1);
            fields.insert(name, (offset, end - offset));
        }
        Struct {
            name: e.name,
            texels: (e.size / 16) as u32,
            fields,
        }
    }
}

/// Each texel view of a struct array in the binding table, by view name.
fn struct_views() -> HashMap<&'static str, Struct> {
    let layouts = rust_layouts();
    BINDINGS
        .iter()
        .filter_map(|b| {
            let Kind::View { of, .. } = b.kind else {
                return None;
            };
            let element = row_of(of).ty.strip_suffix("[]")?;
            let e = layouts.iter().find(|e| e.name == element)?;
            Some((b.name, Struct::new(e)))
        })
        .collect()
}

/// GLSL text without comments and preprocessor lines.
fn strip(glsl: &str) -> String {
    let mut out = String::new();
    let mut rest = glsl;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.find('\n').map_or("", |i| &r[i..]);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.find("*/").map_or("", |i| &r[i + 2..]);
        } else {
            let c = rest.chars().next().expect("not empty");
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    out.lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .collect::<Vec<_>>()
        .join("\n")
}

struct Function {
    name: String,
    params: Vec<String>,
    body: String,
}

/// The functions of a stripped GLSL file (struct declarations skipped).
fn functions(glsl: &str) -> Vec<Function> {
    let mut out = Vec::new();
    let bytes = glsl.as_bytes();
    let mut depth = 0;
    let mut header_start = 0;
    let mut body_start = 0;
    for (i, &c) in bytes.iter().enumerate() {
        match c {
            b'{' => {
                if depth == 0 {
                    body_start = i + 1;
                }
                depth += 1;
            }
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    let header = glsl[header_start..body_start - 1].trim();
                    if let Some(open) = header.find('(') {
                        let name = header[..open].split_whitespace().last().unwrap_or("");
                        let params = header[open + 1..header.rfind(')').unwrap_or(header.len())]
                            .split(',')
                            .filter_map(|p| p.split_whitespace().last().map(str::to_string))
                            .collect();
                        out.push(Function {
                            name: name.to_string(),
                            params,
                            body: glsl[body_start..i].to_string(),
                        });
                    }
                    header_start = i + 1;
                }
            }
            b';' if depth == 0 => header_start = i + 1,
            _ => {}
        }
    }
    out
}

/// Splits at top-level `sep` (outside parentheses).
fn split_top(s: &str, sep: char) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in s.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            c if c == sep && depth == 0 => {
                parts.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[start..]);
    parts
}

/// `s` without an outer `int(...)` or `uint(...)` or `(...)`.
fn unwrap_cast(s: &str) -> &str {
    let s = s.trim();
    for prefix in ["int(", "uint(", "("] {
        if let Some(inner) = s.strip_prefix(prefix).and_then(|r| r.strip_suffix(')'))
            && balanced(inner)
        {
            return unwrap_cast(inner);
        }
    }
    s
}

fn balanced(s: &str) -> bool {
    let mut depth = 0i32;
    for c in s.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0
}

fn is_ident(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn literal(s: &str) -> Option<u32> {
    let s = s.trim();
    s.strip_suffix('u').unwrap_or(s).parse().ok()
}

/// A texel index `stride * i + offset`, or `stride * i + param` in a helper.
#[derive(Clone, Debug, Default)]
struct Index {
    stride: Option<u32>,
    offset: u32,
    param: Option<String>,
}

/// Reads a texel index expression; `locals` are the function's `int x = ...`.
fn index(expr: &str, locals: &HashMap<String, String>, params: &[String]) -> Result<Index, String> {
    let mut out = Index::default();
    for term in split_top(unwrap_cast(expr), '+') {
        let term = unwrap_cast(term);
        if let Some(k) = literal(term) {
            out.offset += k;
        } else if let Some(local) = locals.get(term) {
            let inner = index(local, locals, params)?;
            if out.stride.is_some() || inner.stride.is_none() {
                return Err(format!("index `{expr}`: two struct indices"));
            }
            out.stride = inner.stride;
            out.offset += inner.offset;
        } else if params.iter().any(|p| p == term) && out.stride.is_some() {
            out.param = Some(term.to_string());
        } else {
            let factors = split_top(term, '*');
            let stride = match factors.as_slice() {
                [i] if is_ident(i.trim()) => 1,
                [s, i] if is_ident(i.trim()) => {
                    let s = s.trim();
                    literal(s)
                        .or_else(|| STRIDE_CONSTANTS.iter().find(|c| c.0 == s).map(|c| c.1))
                        .ok_or_else(|| format!("index `{expr}`: unknown stride `{s}`"))?
                }
                _ => return Err(format!("index `{expr}`: not `stride * i + k`")),
            };
            if out.stride.is_some() {
                return Err(format!("index `{expr}`: two struct indices"));
            }
            out.stride = Some(stride);
        }
    }
    Ok(out)
}

/// A function returning `texelFetch(view, int(stride * i + k))` for a
/// parameter `k`: calls to it fetch texel `k` of element `i`.
struct Helper {
    view: String,
    index: Index,
    param_position: usize,
}

/// One texel fetch in a statement: its view, its index, and the swizzle
/// right after it, if any.
struct Fetch {
    view: String,
    index: Index,
    swizzle: Option<String>,
}

/// The identifier ending just before byte `at`, and where it starts.
fn ident_before(s: &str, at: usize) -> Option<(usize, &str)> {
    let start = s[..at]
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |i| i + 1);
    (start < at).then(|| (start, &s[start..at]))
}

/// The swizzle (`.xyz`) starting at byte `at`, if any.
fn swizzle_at(s: &str, at: usize) -> Option<String> {
    let rest = s[at..].strip_prefix('.')?;
    let end = rest
        .find(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .unwrap_or(rest.len());
    let word = &rest[..end];
    (!word.is_empty() && word.chars().all(|c| "xyzw".contains(c))).then(|| word.to_string())
}

/// The arguments of the call whose `(` is at byte `open`, and the byte after `)`.
fn call_args(s: &str, open: usize) -> Option<(Vec<String>, usize)> {
    let mut depth = 0;
    for (i, c) in s[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    let inner = &s[open + 1..open + i];
                    let args = split_top(inner, ',')
                        .into_iter()
                        .map(|a| a.trim().to_string());
                    return Some((args.collect(), open + i + 1));
                }
            }
            _ => {}
        }
    }
    None
}

struct Checker<'a> {
    views: &'a HashMap<&'static str, Struct>,
    helpers: HashMap<String, Helper>,
    errors: Vec<String>,
    /// (struct, field) to how many reads of it were checked.
    checked: BTreeMap<(&'static str, &'static str), usize>,
}

impl Checker<'_> {
    /// Every fetch of a struct texel in `statement`.
    fn fetches(
        &self,
        statement: &str,
        locals: &HashMap<String, String>,
        params: &[String],
    ) -> Result<Vec<Fetch>, String> {
        let mut out = Vec::new();
        for (open, _) in statement.match_indices('(') {
            let Some((_, name)) = ident_before(statement, open) else {
                continue;
            };
            let Some((args, end)) = call_args(statement, open) else {
                continue;
            };
            let (view, index) =
                if (name == "texelFetch" || name == "scene_texel") && args.len() == 2 {
                    if !self.views.contains_key(args[0].as_str()) {
                        continue;
                    }
                    (args[0].clone(), index(&args[1], locals, params)?)
                } else if let Some(h) = self.helpers.get(name) {
                    let k = args.get(h.param_position).and_then(|a| literal(a));
                    let k = k.ok_or_else(|| {
                        format!("`{name}` called with a texel that is not a constant")
                    })?;
                    let mut index = h.index.clone();
                    index.param = None;
                    index.offset += k;
                    (h.view.clone(), index)
                } else {
                    continue;
                };
            out.push(Fetch {
                view,
                index,
                swizzle: swizzle_at(statement, end),
            });
        }
        Ok(out)
    }

    fn check_stride(&mut self, where_: &str, fetch: &Fetch) -> &'static str {
        let s = &self.views[fetch.view.as_str()];
        let stride = fetch.index.stride.unwrap_or(0);
        if stride != s.texels {
            self.errors.push(format!(
                "{where_}: `{}` is indexed with stride {stride}, but a {} is {} texels",
                fetch.view, s.name, s.texels
            ));
        }
        s.name
    }

    /// Checks that texel `texel`, components `swizzle` of `view` hold field
    /// `target` of its struct.
    fn check_field(&mut self, where_: &str, view: &str, texel: u32, swizzle: &str, target: &str) {
        let s = &self.views[view];
        let comps: Vec<usize> = swizzle
            .chars()
            .map(|c| "xyzw".find(c).expect("xyzw"))
            .collect();
        let first = comps[0];
        if comps.iter().enumerate().any(|(k, &c)| c != first + k) {
            self.errors.push(format!(
                "{where_}: `.{swizzle}` is not consecutive components of one field"
            ));
            return;
        }
        let (start, size) = (16 * texel as usize + 4 * first, 4 * comps.len());
        let Some((&field, &(offset, field_size))) = s.fields.get_key_value(target) else {
            self.errors.push(format!(
                "{where_}: texel {texel} `.{swizzle}` of {} goes into `{target}`, which names \
                 no field of {}: name it after the field it holds",
                view, s.name
            ));
            return;
        };
        if (start, size) != (offset, field_size) {
            let want: String = "xyzw"[(offset % 16) / 4..(offset % 16) / 4 + field_size / 4].into();
            self.errors.push(format!(
                "{where_}: `{target}` reads texel {texel} `.{swizzle}` (bytes {start}..{}) of {}, \
                 but {}::{field} is at bytes {offset}..{}: texel {}, `.{want}`",
                start + size,
                view,
                s.name,
                offset + field_size,
                offset / 16
            ));
            return;
        }
        *self.checked.entry((s.name, field)).or_default() += 1;
    }

    /// The field a statement's value goes into: its assignment's target,
    /// or for `return`, the longest field name ending the function's name.
    fn target(&self, statement: &str, function: &str, view: &str) -> Option<String> {
        let s = statement.trim();
        if s.starts_with("return ") {
            let parts: Vec<&str> = function.split('_').collect();
            let fields = &self.views[view].fields;
            return (0..parts.len())
                .map(|k| parts[k..].join("_"))
                .find(|name| fields.contains_key(name.as_str()));
        }
        let eq = s.char_indices().find(|&(i, c)| {
            c == '=' && !s[i + 1..].starts_with('=') && !s[..i].ends_with(['=', '!', '<', '>'])
        })?;
        let lhs = s[..eq.0].trim_end_matches(['*', '+', '-', '/']).trim();
        let name = lhs.rsplit(['.', ' ']).next()?;
        is_ident(name).then(|| name.to_string())
    }

    fn check_function(&mut self, file: &str, f: &Function) {
        let mut locals: HashMap<String, String> = HashMap::new();
        // Row variables: name to (view, texel index).
        let mut rows: HashMap<String, (String, u32)> = HashMap::new();
        let statements: Vec<&str> = f
            .body
            .split([';', '{', '}'])
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        for statement in statements {
            let where_ = format!("{file}: {}()", f.name);
            let flat = statement.split_whitespace().collect::<Vec<_>>().join(" ");
            if let Some(rest) = flat.strip_prefix("int ")
                && let Some((name, value)) = rest.split_once(" = ")
            {
                locals.insert(name.trim().to_string(), value.to_string());
            }
            let fetches = match self.fetches(&flat, &locals, &f.params) {
                Ok(f) => f,
                Err(e) => {
                    self.errors.push(format!("{where_}: {e}"));
                    continue;
                }
            };
            // Reads: swizzled fetches and swizzles of row variables.
            let mut reads: Vec<(String, u32, String)> = Vec::new();
            let mut whole = Vec::new();
            for fetch in &fetches {
                self.check_stride(&where_, fetch);
                match &fetch.swizzle {
                    Some(swizzle) => {
                        reads.push((fetch.view.clone(), fetch.index.offset, swizzle.clone()))
                    }
                    None => whole.push(fetch),
                }
            }
            let declared = flat
                .strip_prefix("uvec4 ")
                .and_then(|r| r.split_once(" = "))
                .map(|(name, _)| name.to_string());
            for (row, (view, texel)) in &rows {
                let mut at = 0;
                while let Some(i) = flat[at..].find(row.as_str()).map(|i| i + at) {
                    at = i + row.len();
                    let before = flat[..i].chars().last();
                    let after = flat[at..].chars().next();
                    let word =
                        |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
                    if word(before) || word(after) || before == Some('.') {
                        continue;
                    }
                    match swizzle_at(&flat, at) {
                        Some(swizzle) => reads.push((view.clone(), *texel, swizzle)),
                        None => self.errors.push(format!(
                            "{where_}: texel row `{row}` of {view} used whole in `{flat}`: read its \
                             fields by swizzle"
                        )),
                    }
                }
            }
            if !whole.is_empty() {
                match (&declared, whole.as_slice(), reads.is_empty()) {
                    (Some(name), [fetch], true) => {
                        rows.insert(name.clone(), (fetch.view.clone(), fetch.index.offset));
                    }
                    _ => self.errors.push(format!(
                        "{where_}: a whole texel read in `{flat}`: assign it alone to a `uvec4` \
                         and read its fields by swizzle"
                    )),
                }
            }
            match reads.as_slice() {
                [] => {}
                [(view, texel, swizzle)] => match self.target(&flat, &f.name, view) {
                    Some(target) => self.check_field(&where_, view, *texel, swizzle, &target),
                    None => self.errors.push(format!(
                        "{where_}: a texel read in `{flat}` goes into no named variable or field"
                    )),
                },
                _ => self.errors.push(format!(
                    "{where_}: several texel reads in `{flat}`: read one field per statement"
                )),
            }
        }
    }
}

/// Checks every texel read of a struct array in `files` (name, GLSL text).
/// Returns one summary line per struct, or every error.
fn check(files: &[(String, String)]) -> Result<Vec<String>, String> {
    let views = struct_views();
    let parsed: Vec<(&str, Vec<Function>)> = files
        .iter()
        .map(|(name, text)| (name.as_str(), functions(&strip(text))))
        .collect();
    let mut checker = Checker {
        views: &views,
        helpers: HashMap::new(),
        errors: Vec::new(),
        checked: BTreeMap::new(),
    };
    // Helpers first: a file may call one defined in another.
    for (_, functions) in &parsed {
        for f in functions {
            let body = f.body.split_whitespace().collect::<Vec<_>>().join(" ");
            let Some(ret) = body
                .strip_prefix("return ")
                .and_then(|r| r.strip_suffix(';'))
            else {
                continue;
            };
            let Ok(fetches) = checker.fetches(ret, &HashMap::new(), &f.params) else {
                continue;
            };
            if let [fetch] = fetches.as_slice()
                && let (Some(param), None) = (&fetch.index.param, &fetch.swizzle)
            {
                let position = f
                    .params
                    .iter()
                    .position(|p| p == param)
                    .expect("a parameter");
                let helper = Helper {
                    view: fetch.view.clone(),
                    index: fetch.index.clone(),
                    param_position: position,
                };
                checker.helpers.insert(f.name.clone(), helper);
            }
        }
    }
    for (file, functions) in &parsed {
        for f in functions {
            if !checker.helpers.contains_key(&f.name) {
                checker.check_function(file, f);
            }
        }
    }
    for s in views.values() {
        if !checker.checked.keys().any(|(name, _)| *name == s.name) {
            checker.errors.push(format!(
                "no checked texel read of {}: is the fetch code still found?",
                s.name
            ));
        }
    }
    if !checker.errors.is_empty() {
        return Err(checker.errors.join("\n"));
    }
    let mut by_struct: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    for ((s, field), n) in &checker.checked {
        by_struct
            .entry(s)
            .or_default()
            .push(format!("{field} x{n}"));
    }
    Ok(by_struct
        .iter()
        .map(|(s, fields)| format!("{s}: {}", fields.join(", ")))
        .collect())
}

/// The renderer's shaders (the benchmark kernels have their own bindings).
fn sources() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut files = Vec::new();
    for dir in ["common", "wavefront"] {
        for entry in std::fs::read_dir(root.join(dir))
            .expect("shader folder")
            .flatten()
        {
            let path = entry.path();
            let text = std::fs::read_to_string(&path).expect("readable shader");
            files.push((
                format!("shaders/{dir}/{}", entry.file_name().to_string_lossy()),
                text,
            ));
        }
    }
    files.sort();
    files
}

/// `sources()` with `from` replaced by `to` in `file` (which must contain it).
fn planted(file: &str, from: &str, to: &str) -> Vec<(String, String)> {
    let mut files = sources();
    let (_, text) = files
        .iter_mut()
        .find(|(name, _)| name.ends_with(file))
        .expect("the file exists");
    assert!(text.contains(from), "{file} no longer contains `{from}`");
    *text = text.replacen(from, to, 1);
    files
}

#[test]
fn every_texel_read_matches_the_rust_layout() {
    match check(&sources()) {
        Ok(lines) => lines.iter().for_each(|l| println!("{l}")),
        Err(e) => panic!("\nthe kernels' texel reads disagree with src/packed/layout.rs:\n{e}\n"),
    }
}

#[test]
fn a_wrong_component_is_reported() {
    let err = check(&planted(
        "scene_fetch.glsl",
        "d.metallic = uintBitsToFloat(t3.y);",
        "d.metallic = uintBitsToFloat(t3.z);",
    ))
    .unwrap_err();
    assert!(
        err.contains("`metallic` reads texel 3 `.z` (bytes 56..60)")
            && err.contains("MaterialData::metallic is at bytes 52..56: texel 3, `.y`"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn a_wrong_texel_is_reported() {
    let err = check(&planted(
        "bvh.glsl",
        "int(3u * i + 1u)).w",
        "int(3u * i + 2u)).w",
    ))
    .unwrap_err();
    assert!(
        err.contains("TriangleVerts::alpha_mask is at bytes 28..32"),
        "{err}"
    );
}

#[test]
fn a_wrong_stride_is_reported() {
    let err = check(&planted(
        "scene_fetch.glsl",
        "int(3u * i)).w",
        "int(4u * i)).w",
    ))
    .unwrap_err();
    assert!(
        err.contains(
            "`tri_shading_texels` is indexed with stride 4, but a TriangleShading is 3 texels"
        ),
        "{err}"
    );
}

#[test]
fn an_unnamed_texel_read_is_reported() {
    let err = check(&planted(
        "textures.glsl",
        "&& base_color_texture != NO_TEXTURE)",
        "&& row6.w != NO_TEXTURE)",
    ))
    .unwrap_err();
    assert!(
        err.contains("goes into no named variable or field"),
        "{err}"
    );
    let err = check(&planted(
        "bvh.glsl",
        "uint child_base_idx = n1.x;",
        "uint first_child = n1.x;",
    ))
    .unwrap_err();
    assert!(
        err.contains("goes into `first_child`, which names no field of CwBvhNode"),
        "{err}"
    );
}

/// The storage binding of a split array covers at most its first part
/// (`packed::bindings`), so a kernel that indexed it would read past it in
/// a large scene: every read goes through the array's views.
#[test]
fn split_arrays_are_read_only_through_their_views() {
    let mut files = sources();
    let loop_kernel =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/path_loop/path_loop.comp");
    files.push((
        "shaders/path_loop/path_loop.comp".into(),
        std::fs::read_to_string(loop_kernel).expect("readable shader"),
    ));
    let split: Vec<&str> = BINDINGS
        .iter()
        .filter(|b| b.owns_buffer() && b.texel_format().is_none() && b.parts_format().is_some())
        .map(|b| b.name)
        .collect();
    assert!(
        split.contains(&"tri_verts") && split.contains(&"tri_texcoords"),
        "{split:?}"
    );
    let mut found = Vec::new();
    for (file, text) in &files {
        let text = strip(text);
        for name in &split {
            for (at, _) in text.match_indices(&format!("{name}[")) {
                let before = text[..at].chars().last();
                if !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.') {
                    found.push(format!("{file}: `{name}[`"));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "split arrays indexed directly:\n{}",
        found.join("\n")
    );
}
