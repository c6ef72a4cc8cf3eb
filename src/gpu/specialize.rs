//! Kernels specialized before lavapipe sees them.
//!
//! lavapipe (Mesa 22.3) turns `shade` into NIR and optimizes it for about
//! 2 s on every run, even when the specialization constants switch nearly
//! all of it off, and it caches nothing of that work. The same module with
//! the constants frozen, the dead branches and functions removed and the
//! rest optimized by SPIRV-Tools' `spirv-opt` (installed with
//! `glslangValidator` on Debian) compiles in 60–150 ms and runs the same
//! arithmetic. `spirv-opt` itself takes 0.7–5 s, so its output is kept in
//! the cache directory, keyed by the module and the constants: a scene's
//! first run pays it once, later runs compile in a fraction of a second.
//!
//! A module read from the cache has its modification time renewed, and
//! whenever one is made, modules unused for `PRUNE_AFTER` are deleted: a
//! vkpt with changed shaders or a scene not rendered again leaves nothing
//! behind for long (each file is 50–200 KB).
//!
//! Without `spirv-opt` or a cache directory nothing changes: the driver
//! gets the module and the constants as before. `VKPT_SPIRV_OPT=off` turns
//! this off; `VKPT_SPIRV_OPT=/path/to/spirv-opt` names the program.

use crate::cache::{FNV_OFFSET, cache_dir, fnv1a, write_atomically};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, SystemTime};

/// The kernels worth it: the others compile in 1–70 ms as they are.
pub const SPECIALIZED_KERNELS: [&str; 3] = ["shade", "shade_basic", "path_loop"];

/// `spirv-opt`'s passes after the constants are set: freeze them, fold the
/// expressions of them (`FEATURE_PBR_EXTENSIONS`) and drop the branches and
/// functions they switch off; inline what can be inlined without
/// `--merge-return`, and turn local variables into SSA values (twice, around
/// scalar replacement), folding constants and dropping dead code as it
/// goes. Mesa then has little left to do. `-O` compiled as fast but ran
/// cornell-spheres' `shade` about 7 percent slower (its `--merge-return`
/// wraps functions in one-iteration loops, which lavapipe runs as loops)
/// and let Mesa fuse other multiply-adds; these passes leave every pixel as
/// the driver's own specialization renders it.
const FREEZE_AND_INLINE: [&str; 6] = [
    "--freeze-spec-const",
    "--fold-spec-const-op-composite",
    "--eliminate-dead-branches",
    "--eliminate-dead-functions",
    "--inline-entry-points-exhaustive",
    "--eliminate-dead-functions",
];

/// Local variables to SSA values, constants propagated, dead code dropped.
const TO_SSA: [&str; 9] = [
    "--private-to-local",
    "--eliminate-local-single-block",
    "--eliminate-local-single-store",
    "--ssa-rewrite",
    "--eliminate-dead-code-aggressive",
    "--ccp",
    "--eliminate-dead-branches",
    "--eliminate-dead-functions",
    "--eliminate-dead-code-aggressive",
];

/// The whole pass list, in order.
fn passes() -> Vec<&'static str> {
    [
        &FREEZE_AND_INLINE[..],
        &TO_SSA,
        &["--scalar-replacement=100"],
        &TO_SSA,
    ]
    .concat()
}

/// Where a kernel's module came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Specialized {
    /// Read from the cache directory.
    Cached(Arc<Vec<u32>>),
    /// Made by `spirv-opt` now (and written to the cache when there is one).
    Made(Arc<Vec<u32>>),
    /// Not specialized, and why: the driver gets the module and constants.
    No(String),
}

impl Specialized {
    /// For the summary line.
    pub fn describe(&self) -> String {
        match self {
            Specialized::Cached(_) => "shade specialized ahead, cached".into(),
            Specialized::Made(_) => "shade specialized ahead by spirv-opt".into(),
            Specialized::No(why) => format!("shade not specialized ahead: {why}"),
        }
    }

    pub fn words(&self) -> Option<&[u32]> {
        match self {
            Specialized::Cached(w) | Specialized::Made(w) => Some(w),
            Specialized::No(_) => None,
        }
    }
}

/// The `spirv-opt` to run, or `None` when turned off.
fn program() -> Option<String> {
    match std::env::var("VKPT_SPIRV_OPT") {
        Ok(v) if v == "off" || v == "0" => None,
        Ok(v) if !v.is_empty() => Some(v),
        _ => Some("spirv-opt".into()),
    }
}

/// The cache key of `spirv` with the constants `values`.
fn key(spirv: &[u8], values: &[u32]) -> u64 {
    let hash = fnv1a(spirv, FNV_OFFSET);
    let hash = fnv1a(bytemuck::cast_slice(values), hash);
    fnv1a(passes().join(" ").as_bytes(), hash)
}

/// SPIR-V words of `bytes`, if they look like a module (magic number,
/// whole words).
fn module_words(bytes: &[u8]) -> Option<Vec<u32>> {
    if bytes.len() < 20 || !bytes.len().is_multiple_of(4) {
        return None;
    }
    let words = crate::gpu::pipeline::spirv_words(bytes);
    (words[0] == 0x0723_0203).then_some(words)
}

/// `spirv-opt`'s `--set-spec-const-default-value` argument: the first
/// `SPEC_COUNT` constants are bools, the rest u32 (`features.glsl`).
fn spec_values_arg(values: &[u32]) -> String {
    values
        .iter()
        .enumerate()
        .map(|(id, &v)| {
            if id < crate::constants::SPEC_COUNT as usize {
                format!("{id}:{}", v != 0)
            } else {
                format!("{id}:{v}")
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Runs `spirv-opt` on `spirv` in `dir` (temporary files named by `stem`).
fn run_spirv_opt(
    program: &str,
    dir: &Path,
    stem: &str,
    spirv: &[u8],
    values: &[u32],
) -> Result<Vec<u32>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let unique = format!(
        "{stem}-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    )
    .replace(|c: char| !c.is_ascii_alphanumeric() && c != '-', "");
    let input = dir.join(format!("{unique}.in.spv"));
    let output = dir.join(format!("{unique}.out.spv"));
    let result = (|| {
        std::fs::write(&input, spirv)
            .map_err(|e| format!("cannot write {}: {e}", input.display()))?;
        let run = Command::new(program)
            .arg("--set-spec-const-default-value")
            .arg(spec_values_arg(values))
            .args(passes())
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .output()
            .map_err(|e| format!("cannot run `{program}` ({e})"))?;
        if !run.status.success() {
            let stderr = String::from_utf8_lossy(&run.stderr);
            return Err(format!("`{program}` failed: {}", stderr.trim()));
        }
        let bytes =
            std::fs::read(&output).map_err(|e| format!("cannot read {}: {e}", output.display()))?;
        module_words(&bytes).ok_or_else(|| format!("`{program}` wrote no SPIR-V module"))
    })();
    let _ = std::fs::remove_file(&input);
    let _ = std::fs::remove_file(&output);
    result
}

/// The cache file of kernel `name` with key `key`.
fn cache_file(dir: &Path, name: &str, key: u64) -> PathBuf {
    dir.join("kernels").join(format!("{name}-{key:016x}.spv"))
}

/// Kernel `name` (`spirv`) specialized to the constants `values`: from the
/// cache, else made by `spirv-opt` and cached. One process makes each
/// module once, however many devices ask for it at once.
pub fn specialize(name: &str, spirv: &[u8], values: &[u32]) -> Specialized {
    let Some(program) = program() else {
        return Specialized::No("VKPT_SPIRV_OPT=off".into());
    };
    // With every feature on there is nothing to remove, and the whole
    // kernel optimized compiles slower, not faster (3.3 s against 2.3 s).
    if values[..] == crate::packed::features::KernelFeatures::ALL.values() {
        return Specialized::No("every feature is on".into());
    }
    let key = key(spirv, values);
    type Slot = Arc<OnceLock<Specialized>>;
    static MADE: OnceLock<Mutex<HashMap<(String, u64), Slot>>> = OnceLock::new();
    let slot = {
        let mut made = MADE
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        made.entry((name.to_string(), key)).or_default().clone()
    };
    slot.get_or_init(|| {
        let dir = cache_dir();
        if let Some(file) = dir.as_ref().map(|d| cache_file(d, name, key))
            && let Some(words) = std::fs::read(&file).ok().and_then(|b| module_words(&b))
        {
            mark_used(&file);
            return Specialized::Cached(Arc::new(words));
        }
        let work_dir = dir
            .as_ref()
            .map(|d| d.join("kernels"))
            .unwrap_or_else(std::env::temp_dir);
        match run_spirv_opt(&program, &work_dir, name, spirv, values) {
            Ok(words) => {
                if let Some(d) = &dir {
                    // A cache that cannot be written costs the next run time,
                    // not this one its kernel.
                    let _ =
                        write_atomically(&cache_file(d, name, key), bytemuck::cast_slice(&words));
                    prune(&d.join("kernels"), SystemTime::now());
                }
                Specialized::Made(Arc::new(words))
            }
            Err(why) => Specialized::No(why),
        }
    })
    .clone()
}

/// How long a cached module may go unused before `prune` deletes it.
pub const PRUNE_AFTER: Duration = Duration::from_secs(30 * 24 * 3600);

/// Renews a cached module's modification time: it was used now. (Reading
/// a file does not change it, and access times are often not kept.)
fn mark_used(file: &Path) {
    if let Ok(f) = std::fs::File::options().append(true).open(file) {
        let _ = f.set_modified(SystemTime::now());
    }
}

/// Deletes the modules in `kernels` (`*.spv`) last used more than
/// `PRUNE_AFTER` before `now`, and the temporary files of `spirv-opt`
/// runs that died as long ago. Errors are ignored: another process may be
/// pruning too, and a file left over costs only disk space.
pub fn prune(kernels: &Path, now: SystemTime) {
    let Ok(entries) = std::fs::read_dir(kernels) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let ours = path.extension().is_some_and(|e| e == "spv");
        let stale = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| now.duration_since(t).ok())
            .is_some_and(|age| age > PRUNE_AFTER);
        if ours && stale {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Forgets a cached module the driver refused, so the next run makes it
/// again instead of failing the same way.
pub fn discard(name: &str, spirv: &[u8], values: &[u32]) {
    if let Some(d) = cache_dir() {
        let _ = std::fs::remove_file(cache_file(&d, name, key(spirv, values)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_values_name_every_constant_as_a_bool() {
        assert_eq!(spec_values_arg(&[1, 0, 1]), "0:true 1:false 2:true");
        let mut values = [1u32; crate::packed::features::SPEC_VALUES];
        values[crate::constants::SPEC_TEXTURE_SLOTS as usize] = 5;
        values[crate::constants::SPEC_SHADE_QUEUE as usize] = 2;
        assert!(spec_values_arg(&values).ends_with(" 17:true 18:true 19:5 20:2 21:1"));
    }

    /// Modules unused for longer than `PRUNE_AFTER` go, the rest stay, and
    /// files that are not modules are left alone.
    #[test]
    fn prune_deletes_only_modules_unused_for_long() {
        let dir = std::env::temp_dir().join(format!("vkpt-prune-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let now = SystemTime::now();
        let day = Duration::from_secs(24 * 3600);
        let files = [
            ("shade-old.spv", now - PRUNE_AFTER - day, false),
            ("shade-recent.spv", now - PRUNE_AFTER + day, true),
            ("shade-new.spv", now, true),
            ("notes.txt", now - PRUNE_AFTER - day, true),
        ];
        for (name, modified, _) in files {
            let f = std::fs::File::create(dir.join(name)).expect("create");
            f.set_modified(modified).expect("set mtime");
        }
        prune(&dir, now);
        for (name, _, kept) in files {
            assert_eq!(dir.join(name).exists(), kept, "{name}");
        }
        // A module read from the cache counts as used now.
        let old = dir.join("shade-old.spv");
        std::fs::File::create(&old)
            .and_then(|f| f.set_modified(now - PRUNE_AFTER - day))
            .expect("old module");
        mark_used(&old);
        prune(&dir, now);
        assert!(old.exists(), "a module just used was pruned");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn keys_differ_by_module_and_constants() {
        let a = key(b"module a", &[1, 0]);
        assert_ne!(a, key(b"module b", &[1, 0]));
        assert_ne!(a, key(b"module a", &[0, 0]));
        assert_eq!(a, key(b"module a", &[1, 0]));
    }

    #[test]
    fn only_whole_spirv_modules_are_read_back() {
        let mut bytes = 0x0723_0203u32.to_le_bytes().to_vec();
        bytes.extend([0u8; 16]);
        assert!(module_words(&bytes).is_some());
        assert!(module_words(&bytes[..19]).is_none());
        bytes[0] = 0;
        assert!(module_words(&bytes).is_none());
    }
}
