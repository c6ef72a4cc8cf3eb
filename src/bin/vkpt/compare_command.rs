//! `vkpt compare A.exr B.exr`: error metrics, then the levelled z-tests
//! (with the noise estimated from the images when a file has no variance
//! layer), and optionally a bound on relMSE.

use crate::args::CompareArgs;

/// Ok(true) when the renders agree.
pub fn run(args: &CompareArgs) -> anyhow::Result<bool> {
    let (a, b) = (&args.a, &args.b);
    let image_a = vkpt::image::read_exr(a)?;
    let image_b = vkpt::image::read_exr(b)?;
    anyhow::ensure!(
        (image_a.width, image_a.height) == (image_b.width, image_b.height),
        "{} is {}x{} but {} is {}x{}",
        a.display(),
        image_a.width,
        image_a.height,
        b.display(),
        image_b.width,
        image_b.height
    );
    let metrics = vkpt::image::metrics::error_metrics(&image_a, &image_b)?;
    println!(
        "relMSE of {} against {}: {:.3e}",
        a.display(),
        b.display(),
        metrics.rel_mse
    );
    println!("{metrics}");
    if let Some(tolerance) = args.tolerance {
        let c = vkpt::image::metrics::closeness(&image_a, &image_b, tolerance)?;
        let same = c.differing == 0 && c.counts_differing == 0;
        println!(
            "{} of {} pixels differ by more than {tolerance:.1e} * (1 + |b|) (largest {:.2e} at \
             ({}, {})); {} pixels have different sample counts: {}",
            c.differing,
            image_a.mean.len(),
            c.largest,
            c.at.0,
            c.at.1,
            c.counts_differing,
            if same { "the same image" } else { "DIFFERENT" }
        );
        return Ok(same);
    }
    let missing: Vec<String> = [(a, &image_a), (b, &image_b)]
        .iter()
        .filter(|(_, image)| image.variance.is_none())
        .map(|(path, _)| path.display().to_string())
        .collect();
    let comparison = if missing.is_empty() {
        vkpt::image::compare::compare(&image_a, &image_b, args.alpha)?
    } else {
        println!(
            "no variance layer in {} (an EXR not written by vkpt?): the noise is estimated from \
             the images themselves",
            missing.join(" and ")
        );
        vkpt::image::estimated_noise::compare_estimating_noise(&image_a, &image_b, args.alpha)?
    };
    println!("{comparison}");
    let mut agree = comparison.passed();
    if let Some(max) = args.max_rel_mse {
        let within = metrics.rel_mse <= max;
        println!(
            "relMSE {:.3e} {} {max:.1e} (--max-rel-mse): {}",
            metrics.rel_mse,
            if within { "<=" } else { ">" },
            if within { "within" } else { "TOO LARGE" }
        );
        agree &= within;
    }
    Ok(agree)
}
