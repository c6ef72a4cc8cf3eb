//! A hash of what a render reads, so parts of one render made on different
//! machines can prove they belong together (`image::RenderHeader::scene_hash`)
//! before `vkpt merge` combines them.
//!
//! It hashes the packed arrays the kernels read, not the scene files: a
//! command-line override (`--env`, `--fstop`, `--background`) changes the
//! image and so the hash, while the same scene at another path does not.
//! Not cryptographic: it guards against mistakes, not adversaries.

use super::PackedScene;
use super::layout::RenderParams;
use crate::splitmix::{GOLDEN_GAMMA, SplitMix64};
use bytemuck::{Pod, bytes_of, cast_slice};

/// A 64-bit multiply-rotate hash over 8-byte words, finished by splitmix64.
struct WordHasher(u64);

impl WordHasher {
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w).wrapping_mul(GOLDEN_GAMMA).rotate_left(31);
    }

    fn bytes(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(u64::from_le_bytes(w.try_into().expect("8 bytes")));
        }
        let mut tail = [0u8; 8];
        tail[..words.remainder().len()].copy_from_slice(words.remainder());
        self.word(u64::from_le_bytes(tail));
        // The length separates arrays, so moving bytes between them counts.
        self.word(bytes.len() as u64);
    }

    fn slice<T: Pod>(&mut self, data: &[T]) {
        self.bytes(cast_slice(data));
    }

    fn finish(&self) -> u64 {
        SplitMix64::new(self.0).next_u64()
    }
}

/// The hash of one array's bytes (the GPU back end re-uploads a buffer
/// between frames only when this changes).
pub fn bytes_hash(bytes: &[u8]) -> u64 {
    let mut h = WordHasher(0x6275_6666_6572_7321);
    h.bytes(bytes);
    h.finish()
}

/// The hash of everything the kernels read about the scene and the view
/// (geometry, BVH, materials, textures, lights, environment, camera, lens,
/// filter), but not the settings a render header names on its own (image
/// size, seed, sampler, depth) nor those that legitimately differ between
/// parts (region, sample range, path pool).
pub fn scene_hash(packed: &PackedScene, params: &RenderParams) -> u64 {
    let view = RenderParams {
        width: 0,
        height: 0,
        max_depth: 0,
        seed: 0,
        rng_sampler: 0,
        pool_size: 0,
        region_x: 0,
        region_y: 0,
        region_width: 0,
        region_height: 0,
        sample_offset: 0,
        aov: 0,
        ..*params
    };
    let mut h = WordHasher(0x766b_7074_7363_656e);
    h.bytes(bytes_of(&view));
    h.slice(&packed.nodes);
    h.slice(&packed.tri_verts);
    h.slice(&packed.tri_shading);
    h.slice(&packed.materials);
    h.slice(&packed.emitters);
    h.slice(&packed.textures.textures);
    h.slice(&packed.textures.texels);
    h.slice(&packed.textures.tri_texcoords);
    h.bytes(bytes_of(&packed.light_params));
    h.slice(&packed.lights);
    h.slice(&packed.env_cdf);
    h.slice(&packed.env_radiance);
    // A moving scene's time steps (a still one hashes as before).
    if let Some(m) = &packed.motion {
        h.slice(&m.texels);
    }
    // A two-level scene's placements (a one-level one hashes as before).
    if !packed.instances.is_empty() {
        h.slice(&packed.instances);
    }
    h.finish()
}

/// `scene_hash` as the 16 hex digits a header records.
pub fn scene_hash_hex(packed: &PackedScene, params: &RenderParams) -> String {
    format!("{:016x}", scene_hash(packed, params))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn word_hasher_sees_every_byte_and_the_boundaries() {
        let hash = |parts: &[&[u8]]| {
            let mut h = WordHasher(1);
            for p in parts {
                h.bytes(p);
            }
            h.finish()
        };
        let base = hash(&[b"0123456789abc"]);
        for i in 0..13 {
            let mut changed = *b"0123456789abc";
            changed[i] ^= 1;
            assert_ne!(hash(&[&changed]), base, "byte {i}");
        }
        assert_ne!(hash(&[b"0123456", b"789abc"]), base);
        assert_ne!(hash(&[b"0123456789abc\0"]), base);
        assert_eq!(hash(&[b"0123456789abc"]), base);
    }
}
