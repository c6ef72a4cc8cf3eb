//! The Rust and GLSL twins of every GPU-visible struct must agree byte for
//! byte: `src/packed/layout.rs` defines them, `shaders/common/types.glsl` declares
//! them again, and a wrong offset gives a wrong image with no validation
//! error. So this test reads the COMPILED SPIR-V of every kernel (not the
//! GLSL text) and checks, for each struct, that the member names and their
//! order, every member's `Offset` decoration and the struct's size (the
//! `ArrayStride` of a runtime array of it where one exists) equal the Rust
//! field names, `offset_of!` and `size_of`, and that every kernel that
//! decorates a struct gives it the same layout.
//!
//! The small SPIR-V reflection below has unit tests of its own, including
//! ones that patch a kernel's offsets and show the comparison catches it.

use crate::struct_layouts;

use std::collections::{BTreeMap, HashMap, HashSet};
use struct_layouts::{Expected, rust_layouts};
use vkpt::gpu::pipeline::{compiled::KERNELS, spirv_local_size, spirv_words};

/// Just enough SPIR-V reflection to recover struct layouts.
mod spirv {
    use super::*;

    const MAGIC: u32 = 0x0723_0203;
    const HEADER_WORDS: usize = 5;

    const OP_NAME: u32 = 5;
    const OP_MEMBER_NAME: u32 = 6;
    const OP_TYPE_INT: u32 = 21;
    const OP_TYPE_FLOAT: u32 = 22;
    const OP_TYPE_VECTOR: u32 = 23;
    const OP_TYPE_ARRAY: u32 = 28;
    const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
    const OP_TYPE_STRUCT: u32 = 30;
    const OP_TYPE_POINTER: u32 = 32;
    const OP_CONSTANT: u32 = 43;
    const OP_DECORATE: u32 = 71;
    const OP_MEMBER_DECORATE: u32 = 72;

    const DECORATION_ARRAY_STRIDE: u32 = 6;
    const DECORATION_OFFSET: u32 = 35;
    const STORAGE_CLASS_UNIFORM: u32 = 2;

    #[derive(Clone, Debug)]
    enum Type {
        /// Int or float, size in bytes.
        Scalar(u32),
        Vector {
            component: u32,
            count: u32,
        },
        Array {
            element: u32,
            length: u32,
        },
        RuntimeArray {
            element: u32,
        },
        Struct(Vec<u32>),
    }

    /// A struct as one module lays it out.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub struct StructLayout {
        pub name: String,
        /// Member names and byte offsets, in declaration order.
        pub members: Vec<(String, u32)>,
        pub size: u32,
        /// Where `size` came from: an `ArrayStride`, or computed.
        pub size_from: &'static str,
    }

    #[derive(Default)]
    struct Module {
        names: HashMap<u32, String>,
        member_names: HashMap<(u32, u32), String>,
        offsets: HashMap<(u32, u32), u32>,
        strides: HashMap<u32, u32>,
        types: HashMap<u32, Type>,
        constants: HashMap<u32, u32>,
        /// Types pointed to by `Uniform` pointers: laid out std140.
        uniform_roots: Vec<u32>,
        /// Struct ids in declaration order.
        structs: Vec<u32>,
    }

    /// A nul-terminated UTF-8 string packed little-endian into words.
    pub fn string(words: &[u32]) -> String {
        let bytes: Vec<u8> = words
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .take_while(|&b| b != 0)
            .collect();
        String::from_utf8_lossy(&bytes).into_owned()
    }

    fn round_up(x: u32, to: u32) -> u32 {
        x.div_ceil(to) * to
    }

    impl Module {
        fn parse(words: &[u32]) -> Result<Module, String> {
            if words.len() < HEADER_WORDS || words[0] != MAGIC {
                return Err("not a SPIR-V module (bad magic or too short)".into());
            }
            let mut m = Module::default();
            let mut i = HEADER_WORDS;
            while i < words.len() {
                let count = (words[i] >> 16) as usize;
                let opcode = words[i] & 0xFFFF;
                if count == 0 || i + count > words.len() {
                    return Err(format!("malformed instruction at word {i}"));
                }
                let op = &words[i + 1..i + count];
                match opcode {
                    OP_NAME if !op.is_empty() => {
                        m.names.insert(op[0], string(&op[1..]));
                    }
                    OP_MEMBER_NAME if op.len() >= 2 => {
                        m.member_names.insert((op[0], op[1]), string(&op[2..]));
                    }
                    OP_DECORATE if op.len() >= 3 && op[1] == DECORATION_ARRAY_STRIDE => {
                        m.strides.insert(op[0], op[2]);
                    }
                    OP_MEMBER_DECORATE if op.len() >= 4 && op[2] == DECORATION_OFFSET => {
                        m.offsets.insert((op[0], op[1]), op[3]);
                    }
                    OP_TYPE_INT | OP_TYPE_FLOAT if op.len() >= 2 => {
                        m.types.insert(op[0], Type::Scalar(op[1] / 8));
                    }
                    OP_TYPE_VECTOR if op.len() >= 3 => {
                        let (component, count) = (op[1], op[2]);
                        m.types.insert(op[0], Type::Vector { component, count });
                    }
                    OP_TYPE_ARRAY if op.len() >= 3 => {
                        let (element, length) = (op[1], op[2]);
                        m.types.insert(op[0], Type::Array { element, length });
                    }
                    OP_TYPE_RUNTIME_ARRAY if op.len() >= 2 => {
                        m.types.insert(op[0], Type::RuntimeArray { element: op[1] });
                    }
                    OP_TYPE_STRUCT if !op.is_empty() => {
                        m.types.insert(op[0], Type::Struct(op[1..].to_vec()));
                        m.structs.push(op[0]);
                    }
                    OP_TYPE_POINTER if op.len() >= 3 && op[1] == STORAGE_CLASS_UNIFORM => {
                        m.uniform_roots.push(op[2]);
                    }
                    OP_CONSTANT if op.len() >= 3 => {
                        m.constants.insert(op[1], op[2]);
                    }
                    _ => {}
                }
                i += count;
            }
            Ok(m)
        }

        fn type_of(&self, id: u32) -> Result<&Type, String> {
            self.types
                .get(&id)
                .ok_or_else(|| format!("type %{id} is not a type this reflection knows"))
        }

        /// Structs reachable from a `Uniform` pointer: these follow std140.
        fn std140_structs(&self) -> HashSet<u32> {
            let mut seen = HashSet::new();
            let mut stack = self.uniform_roots.clone();
            while let Some(id) = stack.pop() {
                match self.types.get(&id) {
                    Some(Type::Struct(members)) if seen.insert(id) => {
                        stack.extend(members.iter().copied())
                    }
                    Some(Type::Array { element, .. } | Type::RuntimeArray { element }) => {
                        stack.push(*element)
                    }
                    _ => {}
                }
            }
            seen
        }

        fn align(&self, id: u32, std140: bool) -> Result<u32, String> {
            Ok(match self.type_of(id)? {
                Type::Scalar(size) => *size,
                Type::Vector { component, count } => {
                    let c = self.size(*component, std140)?;
                    if *count == 3 { 4 * c } else { count * c }
                }
                Type::Array { element, .. } | Type::RuntimeArray { element } => {
                    let a = self.align(*element, std140)?;
                    if std140 { round_up(a, 16) } else { a }
                }
                Type::Struct(members) => {
                    let mut a = 1;
                    for &m in members {
                        a = a.max(self.align(m, std140)?);
                    }
                    if std140 { round_up(a, 16) } else { a }
                }
            })
        }

        /// Size of a struct: the stride of a runtime array of it if there is
        /// one, else end of the last member rounded up to the alignment.
        fn struct_size(&self, id: u32, std140: bool) -> Result<(u32, &'static str), String> {
            let stride = self.types.iter().find_map(|(array, t)| match t {
                Type::RuntimeArray { element } if *element == id => self.strides.get(array),
                _ => None,
            });
            if let Some(&stride) = stride {
                return Ok((stride, "ArrayStride"));
            }
            let Type::Struct(members) = self.type_of(id)? else {
                return Err(format!("%{id} is not a struct"));
            };
            let Some((last, &last_type)) = members.iter().enumerate().next_back() else {
                return Ok((0, "computed"));
            };
            let offset = self.offsets[&(id, last as u32)];
            if let Type::RuntimeArray { .. } = self.type_of(last_type)? {
                // A buffer block like `FilmBlock { FilmPixel film[]; }`.
                return Ok((offset, "fixed part before a runtime array"));
            }
            let end = offset + self.size(last_type, std140)?;
            let rule = if std140 {
                "computed, std140"
            } else {
                "computed, std430"
            };
            Ok((round_up(end, self.align(id, std140)?), rule))
        }

        fn size(&self, id: u32, std140: bool) -> Result<u32, String> {
            Ok(match self.type_of(id)? {
                Type::Scalar(size) => *size,
                Type::Vector { component, count } => count * self.size(*component, std140)?,
                Type::Array { length, .. } => {
                    let stride = self
                        .strides
                        .get(&id)
                        .ok_or_else(|| format!("array %{id} has no ArrayStride"))?;
                    let length = self
                        .constants
                        .get(length)
                        .ok_or_else(|| format!("array %{id}: length is not a constant"))?;
                    stride * length
                }
                Type::RuntimeArray { .. } => {
                    return Err(format!("runtime array %{id} has no size"));
                }
                Type::Struct(_) => self.struct_size(id, std140)?.0,
            })
        }
    }

    /// Every struct in the module whose members all carry an `Offset`
    /// decoration (glslang also emits undecorated copies of a struct for
    /// function-local values; those have no layout and are skipped).
    pub fn decorated_structs(words: &[u32]) -> Result<Vec<StructLayout>, String> {
        let m = Module::parse(words)?;
        let std140 = m.std140_structs();
        let mut out = Vec::new();
        for &id in &m.structs {
            let Type::Struct(members) = &m.types[&id] else {
                unreachable!()
            };
            let offsets: Option<Vec<u32>> = (0..members.len() as u32)
                .map(|k| m.offsets.get(&(id, k)).copied())
                .collect();
            let Some(offsets) = offsets else { continue };
            let members = offsets
                .into_iter()
                .enumerate()
                .map(|(k, offset)| {
                    let name = m.member_names.get(&(id, k as u32)).cloned();
                    (name.unwrap_or_else(|| format!("<member {k}>")), offset)
                })
                .collect();
            let (size, size_from) = m.struct_size(id, std140.contains(&id))?;
            out.push(StructLayout {
                name: m.names.get(&id).cloned().unwrap_or_default(),
                members,
                size,
                size_from,
            });
        }
        Ok(out)
    }
}

use spirv::{StructLayout, decorated_structs};

/// Struct name to every (kernel, layout) that declares it.
type Found<'a> = BTreeMap<String, Vec<(&'a str, StructLayout)>>;

/// Every decorated struct of every module, by struct name, with the name of
/// the module it came from.
fn collect<'a>(
    modules: impl IntoIterator<Item = (&'a str, Vec<u32>)>,
) -> Result<Found<'a>, String> {
    let mut found = Found::new();
    for (kernel, words) in modules {
        for layout in decorated_structs(&words).map_err(|e| format!("kernel '{kernel}': {e}"))? {
            found
                .entry(layout.name.clone())
                .or_default()
                .push((kernel, layout));
        }
    }
    Ok(found)
}

fn describe(layout: &StructLayout) -> String {
    let members: Vec<String> = layout
        .members
        .iter()
        .map(|(name, offset)| format!("{name}@{offset}"))
        .collect();
    format!("{{{}}} size {}", members.join(", "), layout.size)
}

fn kernel_list(kernels: &[&str]) -> String {
    let quoted: Vec<String> = kernels.iter().map(|k| format!("'{k}'")).collect();
    let noun = if kernels.len() == 1 {
        "kernel"
    } else {
        "kernels"
    };
    format!("{noun} {}", quoted.join(", "))
}

/// Compares one Rust struct with every SPIR-V instance of it. Returns a
/// one-line summary, or every disagreement found.
fn check(expected: &Expected, found: &[(&str, StructLayout)]) -> Result<String, String> {
    let name = expected.name;
    if found.is_empty() {
        return Err(format!(
            "struct {name} is laid out in no compiled kernel: is it still declared in \
             shaders/common/types.glsl and used in a buffer, uniform or push-constant block?"
        ));
    }

    // The distinct layouts, each with the kernels that use it.
    let mut layouts: Vec<(&StructLayout, Vec<&str>)> = Vec::new();
    for (kernel, layout) in found {
        let same = |l: &StructLayout| (&l.members, l.size) == (&layout.members, layout.size);
        match layouts.iter_mut().find(|(l, _)| same(l)) {
            Some((_, kernels)) => kernels.push(kernel),
            None => layouts.push((layout, vec![kernel])),
        }
    }
    let mut errors = Vec::new();
    if layouts.len() > 1 {
        let variants: Vec<String> = layouts
            .iter()
            .map(|(l, kernels)| format!("{}: {}", kernel_list(kernels), describe(l)))
            .collect();
        errors.push(format!("{name}: kernels disagree: {}", variants.join("; ")));
    }

    let rust_names: Vec<&str> = expected.fields.iter().map(|f| f.0).collect();
    for (spirv, kernels) in &layouts {
        let at = kernel_list(kernels);
        let spirv_names: Vec<&str> = spirv.members.iter().map(|m| m.0.as_str()).collect();
        if rust_names != spirv_names {
            errors.push(format!(
                "{name}: members differ: Rust {rust_names:?}, SPIR-V {spirv_names:?} ({at})"
            ));
        }
        for (k, &(field, rust_offset)) in expected.fields.iter().enumerate() {
            match spirv.members.get(k) {
                Some((member, offset)) if *offset as usize != rust_offset => errors.push(format!(
                    "{name}.{field}: Rust offset {rust_offset}, SPIR-V offset {offset} \
                         (member {k} '{member}', {at})"
                )),
                _ => {}
            }
        }
        if spirv.size as usize != expected.size {
            errors.push(format!(
                "{name}: Rust size {}, SPIR-V size {} ({}, {at})",
                expected.size, spirv.size, spirv.size_from
            ));
        }
    }

    if !errors.is_empty() {
        return Err(errors.join("\n"));
    }
    let spirv = layouts[0].0;
    Ok(format!(
        "{name:<16} {:>2} members, size {:>3} ({}), offsets {:?} agree in {} kernels",
        spirv.members.len(),
        spirv.size,
        spirv.size_from,
        spirv.members.iter().map(|m| m.1).collect::<Vec<_>>(),
        found.len(),
    ))
}

/// Checks every Rust struct against the modules; the summary lines, or all
/// disagreements.
fn check_all<'a>(
    modules: impl IntoIterator<Item = (&'a str, Vec<u32>)>,
) -> Result<Vec<String>, String> {
    let found = collect(modules)?;
    let mut summaries = Vec::new();
    let mut errors = Vec::new();
    for expected in rust_layouts() {
        let instances = found.get(expected.name).map_or(&[][..], |v| v.as_slice());
        match check(&expected, instances) {
            Ok(line) => summaries.push(line),
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        Ok(summaries)
    } else {
        Err(errors.join("\n"))
    }
}

fn kernel_modules() -> Vec<(&'static str, Vec<u32>)> {
    assert!(!KERNELS.is_empty(), "no compiled kernels");
    KERNELS
        .iter()
        .map(|&(name, bytes)| (name, spirv_words(bytes)))
        .collect()
}

#[test]
fn rust_and_glsl_layouts_agree() {
    match check_all(kernel_modules()) {
        Ok(lines) => {
            for line in lines {
                println!("{line}");
            }
        }
        Err(e) => panic!(
            "\nsrc/layout.rs and shaders/common/types.glsl disagree:\n{e}\n\
             (fix whichever side is wrong; they must match field for field)\n"
        ),
    }
}

/// Calls `f` with the words of every instruction of a module.
fn for_each_instruction(words: &mut [u32], mut f: impl FnMut(&mut [u32])) {
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        f(&mut words[i..i + count]);
        i += count;
    }
}

/// Sets the `Offset` decoration of `struct_name`'s member `member` to
/// `offset` in a module, as a wrong GLSL declaration would. Returns whether
/// the module had such a decoration.
fn patch_offset(words: &mut [u32], struct_name: &str, member: u32, offset: u32) -> bool {
    let mut ids = HashSet::new();
    for_each_instruction(words, |w| {
        if w[0] & 0xFFFF == 5 && spirv::string(&w[2..]) == struct_name {
            ids.insert(w[1]);
        }
    });
    let mut patched = false;
    for_each_instruction(words, |w| {
        if w[0] & 0xFFFF == 72 && ids.contains(&w[1]) && w[2] == member && w[3] == 35 {
            w[4] = offset;
            patched = true;
        }
    });
    patched
}

#[test]
fn a_wrong_offset_in_one_kernel_is_reported() {
    // Move CwBvhNode's second member onto its last one's offset, as a GLSL
    // declaration with two members swapped would.
    let layouts = rust_layouts();
    let bvh = layouts.iter().find(|e| e.name == "CwBvhNode").unwrap();
    let (field, rust_offset) = bvh.fields[1];
    let wrong = bvh.fields.last().unwrap().1 as u32;
    let expected_line = format!(
        "CwBvhNode.{field}: Rust offset {rust_offset}, SPIR-V offset {wrong} (member 1 '{field}'"
    );

    let mut modules = kernel_modules();
    let (kernel, words) = modules
        .iter_mut()
        .find(|(_, w)| {
            decorated_structs(w)
                .unwrap()
                .iter()
                .any(|s| s.name == "CwBvhNode")
        })
        .expect("some kernel reads CwBvhNode");
    assert!(patch_offset(words, "CwBvhNode", 1, wrong));
    let kernel = *kernel;
    let err = check_all(modules).expect_err("a patched offset must fail the check");
    println!("{err}");
    assert!(err.contains("CwBvhNode: kernels disagree"), "{err}");
    assert!(
        err.contains(&format!("{expected_line}, kernel '{kernel}')")),
        "{err}"
    );
    // Only CwBvhNode is wrong.
    assert!(err.lines().all(|l| l.starts_with("CwBvhNode")), "{err}");

    // The same patch in every kernel: they agree with each other, not with Rust.
    let mut modules = kernel_modules();
    for (_, words) in &mut modules {
        patch_offset(words, "CwBvhNode", 1, wrong);
    }
    let err = check_all(modules).expect_err("a patched offset must fail the check");
    assert!(!err.contains("kernels disagree"), "{err}");
    assert!(err.contains(&expected_line), "{err}");
}

#[test]
fn a_struct_in_no_kernel_is_reported() {
    let modules = kernel_modules()
        .into_iter()
        .map(|(name, mut words)| {
            // Rename every "FilmPixel" struct to "FilmPixeX": the string
            // starts at operand word 2 (after the target id), and byte 8,
            // the final 'l', is the low byte of its third word.
            for_each_instruction(&mut words, |w| {
                if w[0] & 0xFFFF == 5 && spirv::string(&w[2..]) == "FilmPixel" {
                    w[4] = (w[4] & !0xFF) | u32::from(b'X');
                }
            });
            (name, words)
        })
        .collect::<Vec<_>>();
    let err = check_all(modules).expect_err("a missing struct must fail the check");
    assert!(
        err.contains("struct FilmPixel is laid out in no compiled kernel"),
        "{err}"
    );
}

/// A hand-built module: `struct Pair { uint a; uint b; }` with `Offset`
/// decorations, optionally in a runtime array of stride 8, plus an
/// undecorated copy of it as glslang emits for function-local values.
fn hand_built_module(with_array: bool) -> Vec<u32> {
    fn inst(opcode: u32, operands: &[u32]) -> Vec<u32> {
        let mut w = vec![((operands.len() as u32 + 1) << 16) | opcode];
        w.extend_from_slice(operands);
        w
    }
    fn named(id: &[u32], s: &str) -> Vec<u32> {
        let mut bytes = s.as_bytes().to_vec();
        bytes.push(0);
        bytes.resize(bytes.len().div_ceil(4) * 4, 0);
        [id, &spirv_words(&bytes)].concat()
    }
    let (pair, uint, array, local_pair) = (1, 2, 3, 4);
    let mut words = vec![0x0723_0203, 0x0001_0500, 0, 5, 0];
    for id in [pair, local_pair] {
        words.extend(inst(5, &named(&[id], "Pair")));
        words.extend(inst(6, &named(&[id, 0], "a")));
        words.extend(inst(6, &named(&[id, 1], "b")));
    }
    words.extend(inst(72, &[pair, 0, 35, 0]));
    words.extend(inst(72, &[pair, 1, 35, 4]));
    if with_array {
        words.extend(inst(71, &[array, 6, 8]));
    }
    words.extend(inst(21, &[uint, 32, 0]));
    words.extend(inst(30, &[pair, uint, uint]));
    if with_array {
        words.extend(inst(29, &[array, pair]));
    }
    words.extend(inst(30, &[local_pair, uint, uint]));
    words
}

#[test]
fn reflection_of_a_hand_built_module() {
    let structs = decorated_structs(&hand_built_module(true)).unwrap();
    assert_eq!(
        structs,
        vec![StructLayout {
            name: "Pair".into(),
            members: vec![("a".into(), 0), ("b".into(), 4)],
            size: 8,
            size_from: "ArrayStride",
        }]
    );
    let found = vec![("hand-built", structs[0].clone())];
    let good = Expected {
        name: "Pair",
        size: 8,
        fields: &[("a", 0), ("b", 4)],
    };
    assert!(check(&good, &found).is_ok());
    let moved = Expected {
        name: "Pair",
        size: 8,
        fields: &[("a", 0), ("b", 8)],
    };
    let err = check(&moved, &found).unwrap_err();
    assert!(
        err.contains("Pair.b: Rust offset 8, SPIR-V offset 4"),
        "{err}"
    );
    let renamed = Expected {
        name: "Pair",
        size: 12,
        fields: &[("a", 0), ("c", 4)],
    };
    let err = check(&renamed, &found).unwrap_err();
    assert!(err.contains("members differ"), "{err}");
    assert!(err.contains("Rust size 12, SPIR-V size 8"), "{err}");

    // Without the runtime array the size is computed: end of `b`, aligned to 4.
    let structs = decorated_structs(&hand_built_module(false)).unwrap();
    assert_eq!(structs.len(), 1);
    assert_eq!(
        (structs[0].size, structs[0].size_from),
        (8, "computed, std430")
    );

    assert!(decorated_structs(&[1, 2, 3, 4, 5]).is_err());
}

#[test]
fn local_size_is_read_from_spirv() {
    let words = |name: &str| {
        let &(_, bytes) = KERNELS
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("kernel '{name}' is not compiled"));
        spirv_words(bytes)
    };
    assert_eq!(spirv_local_size(&words("extend")).unwrap(), [64, 1, 1]);
    assert_eq!(
        spirv_local_size(&words("ray_queue_args")).unwrap(),
        [1, 1, 1]
    );
    assert!(spirv_local_size(&[0; 8]).is_err());
}
