use super::Scene;
use std::path::Path;

pub fn load_gltf(path: &Path) -> anyhow::Result<Scene> {
    anyhow::bail!("{}: glTF loading is not written yet", path.display())
}
