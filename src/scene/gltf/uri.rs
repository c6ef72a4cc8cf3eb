//! Where a glTF file's URIs may point. A scene reads files from its own
//! folder only: after percent-decoding, an absolute path, a `..` that climbs
//! above the folder, or a symbolic link that resolves outside it is refused
//! unless the caller allows it (`LoadOptions::allow_outside_uris`). (A scene unpacked from an
//! archive may carry symlinks, so they are checked where they lead, not
//! where they sit.) `data:` URIs carry their bytes and are always fine.

use anyhow::{Result, bail};
use std::path::{Component, Path, PathBuf};

/// Decodes `%XX` escapes in a relative URI (glTF URIs are RFC 3986).
pub(super) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(v) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The file a relative `uri` names, relative to the scene's folder `base`.
/// Errors (without naming the element; the caller adds it) when the URI
/// leaves `base` and `allow_outside` is false.
pub(super) fn resolve(base: &Path, uri: &str, allow_outside: bool) -> Result<PathBuf> {
    let decoded = percent_decode(uri);
    let file = base.join(&decoded);
    if allow_outside {
        return Ok(file);
    }
    let hint = "allow it with LoadOptions::allow_outside_uris";
    let rel = Path::new(&decoded);
    // `C:` or `\\server` count as absolute on every platform: the file may
    // have been written on Windows.
    let drive = decoded.len() >= 2 && decoded.as_bytes()[1] == b':';
    if rel.has_root() || decoded.starts_with('\\') || drive {
        bail!(
            "uri {uri:?} is an absolute path; vkpt reads only files in the scene's folder ({hint})"
        );
    }
    let mut depth = 0usize;
    for c in rel.components() {
        match c {
            Component::ParentDir if depth == 0 => bail!(
                "uri {uri:?} points outside the scene's folder {} ({hint})",
                display_dir(base)
            ),
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            _ => {}
        }
    }
    // Symbolic links: compare where the file really is with the folder.
    if let (Ok(real), Ok(real_base)) = (file.canonicalize(), base_dir(base).canonicalize())
        && !real.starts_with(&real_base)
    {
        bail!(
            "uri {uri:?} resolves (through a symbolic link) to {}, outside the scene's folder {} ({hint})",
            real.display(),
            real_base.display()
        );
    }
    Ok(file)
}

/// `base` as a directory that exists for a relative scene path ("" is ".").
fn base_dir(base: &Path) -> &Path {
    if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    }
}

fn display_dir(base: &Path) -> String {
    base_dir(base).display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_inside_the_folder_resolve() {
        let base = Path::new("scenes");
        assert_eq!(
            resolve(base, "a%20b.bin", false).unwrap(),
            Path::new("scenes/a b.bin")
        );
        assert!(resolve(base, "sub/../x.bin", false).is_ok());
        assert!(resolve(base, "./sub/x.bin", false).is_ok());
    }

    #[test]
    fn escaping_uris_are_refused_unless_allowed() {
        let base = Path::new("scenes");
        for uri in [
            "../secret",
            "../../secret",
            "sub/../../secret",
            "%2e%2e/secret",
            "%2E%2E%2Fsecret",
            "/etc/passwd",
            "%2Fetc/passwd",
            "C:/Windows/win.ini",
            "\\\\server\\share",
        ] {
            let err = resolve(base, uri, false).expect_err(uri).to_string();
            assert!(err.contains("allow_outside_uris"), "{uri}: {err}");
            assert!(resolve(base, uri, true).is_ok(), "{uri}");
        }
    }
}
