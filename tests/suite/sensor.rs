//! `--sensor bayer` from the command line: a small Cornell box on the CPU
//! back end writes the demosaiced image (R, G, B, without variance and
//! samples) and the raw mosaic (one channel), in EXR and PNG.

use crate::common;

use common::vkpt;
use std::path::Path;

/// The channel names of an EXR's first layer, sorted.
fn channels(path: &Path) -> Vec<String> {
    let image = exr::prelude::read_all_data_from_file(path).expect("reads the EXR");
    let mut names: Vec<String> = image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    names.sort();
    names
}

#[test]
fn bayer_sensor_writes_demosaiced_image_and_raw_mosaic() {
    let dir = common::output_dir("sensor");
    let image = dir.join("cornell-bayer.exr");
    let mosaic = dir.join("mosaic.exr");
    let mosaic_png = dir.join("mosaic.png");
    for p in [&image, &mosaic, &mosaic_png] {
        let _ = std::fs::remove_file(p);
    }
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4",
        "--device",
        "cpu",
        "--quiet",
        "--sensor",
        "bayer",
        "--raw-mosaic",
        mosaic.to_str().unwrap(),
        "-o",
        image.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("note: --sensor bayer"), "{err}");
    assert_eq!(channels(&image), ["B", "G", "R"]);
    assert_eq!(channels(&mosaic), ["Y"]);
    let m = exr::prelude::read_first_flat_layer_from_file(&mosaic).expect("reads the mosaic");
    assert_eq!(m.layer_data.size.0, 32);
    assert_eq!(m.layer_data.size.1, 32);

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4",
        "--device",
        "cpu",
        "--quiet",
        "--sensor",
        "bayer",
        "--sensor-noise",
        "off",
        "--demosaic",
        "bilinear",
        "--sensor-bits",
        "10",
        "--raw-mosaic",
        mosaic_png.to_str().unwrap(),
        "-o",
        dir.join("cornell-bayer.png").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = image::open(&mosaic_png).expect("reads the PNG mosaic");
    assert_eq!(png.color(), image::ColorType::L16);
    assert_eq!((png.width(), png.height()), (32, 32));
}

#[test]
fn raw_mosaic_needs_the_bayer_sensor() {
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--width",
        "8",
        "--device",
        "cpu",
        "--raw-mosaic",
        "target/test-output/sensor/never.exr",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--raw-mosaic needs --sensor bayer"));
}

#[test]
fn help_explains_the_sensor_flags() {
    let o = vkpt(&["--help"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "--sensor <S>",
        "RGGB",
        "--sensor-bits <N>",
        "--sensor-noise <on|off>",
        "--demosaic <M>",
        "Malvar",
        "--raw-mosaic <FILE>",
    ] {
        assert!(text.contains(needle), "--help does not mention {needle}");
    }
}
