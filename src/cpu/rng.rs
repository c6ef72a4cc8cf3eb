//! Twin of `shaders/common/rng.glsl`: wrapping arithmetic reproduces GLSL `uint`.

pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

pub fn rng_path_key(pixel: u32, sample_index: u32, seed: u32) -> u32 {
    pcg_hash(pcg_hash(pcg_hash(sample_index).wrapping_add(pixel)).wrapping_add(seed))
}

pub fn rng_float(key: u32, dim: u32) -> f32 {
    (pcg_hash(key.wrapping_add(pcg_hash(dim))) >> 8) as f32 * (1.0 / 16777216.0)
}

pub fn rng_float2(key: u32, dim: u32) -> glam::Vec2 {
    glam::Vec2::new(rng_float(key, dim), rng_float(key, dim + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_float_is_in_unit_interval_and_uniform() {
        let mut bins = [0u32; 16];
        for i in 0..160_000u32 {
            let u = rng_float(rng_path_key(i % 977, i / 977, 7), i % 13);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 16.0) as usize] += 1;
        }
        // Chi-square with 15 degrees of freedom; 37.7 is the 0.001 quantile.
        let chi2: f64 = bins
            .iter()
            .map(|&b| (b as f64 - 10_000.0).powi(2) / 10_000.0)
            .sum();
        assert!(chi2 < 37.7, "chi2 = {chi2}");
    }

    #[test]
    fn different_seeds_give_different_streams() {
        let same = (0..1000)
            .filter(|&d| rng_float(rng_path_key(5, 3, 0), d) == rng_float(rng_path_key(5, 3, 1), d))
            .count();
        assert!(same < 5);
    }
}
