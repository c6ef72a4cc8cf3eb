//! A glTF buffer's bytes: an external `.bin` file mapped into memory, a
//! `.glb`'s BIN chunk inside its mapped file, or bytes held in a vector
//! (data URIs, decoded compressed geometry, and files that cannot be
//! mapped).
//!
//! Mapping skips the copy `fs::read` makes out of the page cache: on a
//! 120 MB file that copy (and the fresh pages it fills) took a sixth of
//! the load's CPU time (docs/performance.md, "Load time"). The map is
//! read-only and private, as most tools that map their inputs do: another
//! program that rewrites the file meanwhile changes only values, which
//! the decoder checks as it reads them; one that truncates it makes reads
//! past the new end fault (SIGBUS). The map lives as long as the
//! [`Buffer`]; the command line drops the file's buffers before the BVH
//! build.

use anyhow::{Context, Result};
use std::ops::Deref;
use std::path::Path;

/// A buffer's bytes, read or mapped.
pub(super) enum Buffer {
    Owned(Vec<u8>),
    #[cfg(unix)]
    Mapped(Mapping),
    /// Bytes `range` of another buffer: a `.glb`'s BIN chunk inside the
    /// file, neither copied nor read twice.
    Part {
        whole: Box<Buffer>,
        range: std::ops::Range<usize>,
    },
}

impl Deref for Buffer {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Buffer::Owned(v) => v,
            #[cfg(unix)]
            Buffer::Mapped(m) => m,
            Buffer::Part { whole, range } => &whole[range.clone()],
        }
    }
}

impl From<Vec<u8>> for Buffer {
    fn from(v: Vec<u8>) -> Buffer {
        Buffer::Owned(v)
    }
}

impl Buffer {
    /// Bytes `range` of this buffer (which must hold them), keeping the
    /// rest alive with it.
    pub fn part(self, range: std::ops::Range<usize>) -> Buffer {
        assert!(range.start <= range.end && range.end <= self.len());
        Buffer::Part {
            whole: Box::new(self),
            range,
        }
    }

    /// The bytes of the file at `path`: mapped when it is a regular,
    /// non-empty file the system lets map, else read. Errors are the
    /// system's; the caller names the file.
    pub fn from_file(path: &Path) -> Result<Buffer> {
        #[cfg(unix)]
        if let Some(m) = Mapping::of(path)? {
            return Ok(Buffer::Mapped(m));
        }
        Ok(Buffer::Owned(std::fs::read(path)?))
    }
}

/// A file mapped read-only, unmapped on drop.
#[cfg(unix)]
pub(super) struct Mapping {
    ptr: std::ptr::NonNull<u8>,
    len: usize,
}

// SAFETY: the mapping is read-only and owned by this value alone; nothing
// writes through it.
#[cfg(unix)]
unsafe impl Send for Mapping {}
// SAFETY: as above; shared reads of read-only memory.
#[cfg(unix)]
unsafe impl Sync for Mapping {}

#[cfg(unix)]
impl Mapping {
    /// The file mapped, or None when it is not something to map (not a
    /// regular file, empty, or the system refuses): then it is read.
    fn of(path: &Path) -> Result<Option<Mapping>> {
        use std::os::fd::AsRawFd;
        let file = std::fs::File::open(path)?;
        let meta = file.metadata().context("cannot stat it")?;
        let Ok(len) = usize::try_from(meta.len()) else {
            return Ok(None);
        };
        if !meta.is_file() || len == 0 {
            return Ok(None);
        }
        // SAFETY: a fresh private read-only mapping of an open file; the
        // kernel picks the address. The descriptor may close afterwards.
        let ptr = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ,
                libc::MAP_PRIVATE,
                file.as_raw_fd(),
                0,
            )
        };
        if ptr == libc::MAP_FAILED {
            return Ok(None);
        }
        let ptr = std::ptr::NonNull::new(ptr.cast::<u8>()).expect("mmap never returns null");
        Ok(Some(Mapping { ptr, len }))
    }
}

#[cfg(unix)]
impl Deref for Mapping {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        // SAFETY: `len` bytes mapped readable at `ptr` until drop.
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }
}

#[cfg(unix)]
impl Drop for Mapping {
    fn drop(&mut self) {
        // SAFETY: the range this value mapped; no slice of it outlives
        // `self` (they borrow it).
        unsafe { libc::munmap(self.ptr.as_ptr().cast(), self.len) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("vkpt-buffer-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A mapped file holds the bytes `fs::read` reads, past a page
    /// boundary and up to a length that is not a multiple of a page.
    #[test]
    fn a_mapped_file_reads_what_fs_read_reads() {
        let dir = temp_dir("same");
        let path = dir.join("data.bin");
        let bytes: Vec<u8> = (0..3 * 4096 + 123u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
            .collect();
        std::fs::write(&path, &bytes).unwrap();
        let buffer = Buffer::from_file(&path).unwrap();
        #[cfg(unix)]
        assert!(matches!(buffer, Buffer::Mapped(_)), "not mapped");
        assert_eq!(&buffer[..], &std::fs::read(&path).unwrap()[..]);
        drop(buffer);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Files that cannot be mapped are read (empty) or refused (a
    /// directory, a missing file) without a panic.
    #[test]
    fn empty_missing_and_directory_files() {
        let dir = temp_dir("odd");
        let empty = dir.join("empty.bin");
        std::fs::write(&empty, b"").unwrap();
        assert!(Buffer::from_file(&empty).unwrap().is_empty());
        assert!(Buffer::from_file(&dir.join("missing.bin")).is_err());
        assert!(Buffer::from_file(&dir).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
