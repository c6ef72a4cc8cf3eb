//! Photometric stereo end to end (`examples/photometric_stereo.rs`, run here
//! at a small size): the sphere's normals and albedo are recovered from four
//! renders under known directional lights, and interreflection from a floor
//! visibly breaks the method's assumption.

#[path = "../../examples/photometric_stereo.rs"]
mod example;

#[test]
fn photometric_stereo_recovers_the_spheres_normals_and_albedo() {
    let r = example::photometric_stereo(48, 4, false);
    println!(
        "sphere alone: {} pixels, mean {:.4} deg, p95 {:.4} deg, albedo {:.4}",
        r.pixels, r.mean_angle_deg, r.p95_angle_deg, r.mean_albedo
    );
    assert!(r.pixels > 1000, "too few pixels solved: {}", r.pixels);
    assert!(
        r.mean_angle_deg < 1.0,
        "mean normal error {} deg",
        r.mean_angle_deg
    );
    assert!(
        r.p95_angle_deg < 1.0,
        "95th percentile {} deg",
        r.p95_angle_deg
    );
    assert!(
        (r.mean_albedo - 0.7).abs() < 0.007,
        "albedo {}",
        r.mean_albedo
    );
}

#[test]
fn interreflection_from_a_floor_biases_photometric_stereo() {
    let r = example::photometric_stereo(48, 16, true);
    println!(
        "on a floor: {} pixels, mean {:.2} deg, p95 {:.2} deg, albedo {:.4}",
        r.pixels, r.mean_angle_deg, r.p95_angle_deg, r.mean_albedo
    );
    // Light off the floor reaches the sphere's underside: I = L G no longer
    // holds there, and the solve tilts the normals.
    assert!(
        r.mean_angle_deg > 5.0,
        "mean normal error only {} deg",
        r.mean_angle_deg
    );
}
