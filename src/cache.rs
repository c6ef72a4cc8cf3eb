//! Where vkpt keeps what it can rebuild but would rather not: compiled
//! pipelines (`gpu/pipeline_cache.rs`) and the benchmark's converged
//! reference images (`bench/reference.rs`).

use std::path::PathBuf;

/// `$VKPT_CACHE_DIR`, else `$XDG_CACHE_HOME/vkpt`, else `~/.cache/vkpt` (the
/// XDG base directory default). `None` when none is set, or when
/// `VKPT_CACHE_DIR` is set but empty (caching off).
pub fn cache_dir() -> Option<PathBuf> {
    let non_empty = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(v) = std::env::var_os("VKPT_CACHE_DIR") {
        return (!v.is_empty()).then(|| PathBuf::from(v));
    }
    if let Some(xdg) = non_empty("XDG_CACHE_HOME") {
        return Some(PathBuf::from(xdg).join("vkpt"));
    }
    non_empty("HOME").map(|home| PathBuf::from(home).join(".cache").join("vkpt"))
}

/// 64-bit FNV-1a: a stable content hash for cache keys (not for security).
pub fn fnv1a(bytes: &[u8], mut hash: u64) -> u64 {
    for &b in bytes {
        hash ^= b as u64;
        hash = hash.wrapping_mul(0x0000_0100_0000_01B3);
    }
    hash
}

/// FNV-1a's offset basis, the hash of nothing.
pub const FNV_OFFSET: u64 = 0xCBF2_9CE4_8422_2325;

/// Writes `bytes` to `path` through a temporary file and a rename, so a
/// reader never sees half a file and two writers never interleave.
pub fn write_atomically(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_fnv1a_known_values() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a(b"", FNV_OFFSET), 0xCBF2_9CE4_8422_2325);
        assert_eq!(fnv1a(b"a", FNV_OFFSET), 0xAF63_DC4C_8601_EC8C);
        assert_eq!(fnv1a(b"foobar", FNV_OFFSET), 0x8594_4171_F739_67E8);
    }
}
