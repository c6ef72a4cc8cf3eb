//! `vkpt merge PART.exr... -o OUT.exr`: check that the parts belong
//! together, combine them (`vkpt::film::merge`), write atomically.

use crate::args::MergeArgs;
use vkpt::image::write_image_with_header;

pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let out = &args.output;
    let is_exr = out
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    anyhow::ensure!(
        is_exr,
        "{}: vkpt merge writes .exr (the merged image keeps its variance and header)",
        out.display()
    );
    let merged =
        vkpt::film::merge::merge_files(&args.parts, args.allow_holes, args.samples.clone())?;
    let h = &merged.header;
    write_image_with_header(out, &merged.image, &Default::default(), Some(h))?;
    if merged.holes > 0 {
        eprintln!(
            "note: {} pixels are in no part and were left black with no samples (--allow-holes)",
            merged.holes
        );
    }
    println!(
        "merged {} parts ({} region{}) into {}x{}, samples {}..{} ({} spp): wrote {}",
        merged.parts,
        merged.regions,
        if merged.regions == 1 { "" } else { "s" },
        h.width,
        h.height,
        h.samples.start,
        h.samples.end,
        h.samples.len(),
        out.display()
    );
    Ok(())
}
