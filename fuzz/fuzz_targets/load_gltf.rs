//! Feeds arbitrary bytes to the glTF loader as a `.glb` (when they start
//! with the GLB magic) or a `.gltf`, then packs what loads (BVH build
//! included). Any panic, abort or sanitizer report is a bug: bad input must
//! come back as an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use vkpt::packed::PackedScene;
use vkpt::scene::Scene;

fn scratch(ext: &str) -> PathBuf {
    // tmpfs when there is one: the loader reads from a path.
    let dir = if std::path::Path::new("/dev/shm").is_dir() {
        PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    dir.join(format!("vkpt-fuzz-{}.{ext}", std::process::id()))
}

fuzz_target!(|data: &[u8]| {
    let path = scratch(if data.starts_with(b"glTF") { "glb" } else { "gltf" });
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(scene) = Scene::load(&path) {
        let _ = PackedScene::new(&scene);
    }
    let _ = std::fs::remove_file(&path);
});
