//! The library's errors name its settings (`LoadOptions::allow_outside_uris`);
//! a command-line user needs the flag that sets them. The one table of that
//! mapping, applied to every error the command prints.

/// (what the library says, what the command line calls it).
const SETTING_FLAGS: &[(&str, &str)] = &[
    ("LoadOptions::allow_outside_uris", "--allow-outside-uris"),
    ("CameraOverrides::focus_distance", "--focus-distance"),
    ("DeviceChoice::Cpu", "--device cpu"),
    ("VulkanDevice::Best", "--device auto"),
    ("VulkanDevice::Hardware", "--device gpu"),
    ("VulkanDevice::Lavapipe", "--device lavapipe"),
    ("BenchConfig::reference_spp", "--reference-spp"),
    ("BenchConfig::reference", "--reference"),
    ("BenchConfig::width and height", "--width/--height"),
];

/// The library's setting names in `text` replaced by flags.
pub fn in_flags(text: &str) -> String {
    let mut text = text.to_string();
    for (setting, flag) in SETTING_FLAGS {
        text = text.replace(setting, flag);
    }
    text
}

/// `error: ...`, in flags.
pub fn print_error(e: &anyhow::Error) {
    eprintln!("error: {}", in_flags(&format!("{e:#}")));
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_mapped_setting_exists_in_the_library_source() {
        // A renamed setting would leave its row unused: find each one.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut sources = String::new();
        let mut stack = vec![root];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).expect("src is readable").flatten() {
                let path = entry.path();
                if path.is_dir() && !path.ends_with("bin") {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    sources += &std::fs::read_to_string(&path).expect("readable source");
                }
            }
        }
        for (setting, _) in super::SETTING_FLAGS {
            let name = setting.split("::").next().expect("Type::name");
            let setting = setting.split(' ').next().expect("a first word");
            assert!(
                sources.contains(setting) || setting.starts_with("VulkanDevice"),
                "{setting} is not named anywhere in the library"
            );
            assert!(sources.contains(name), "no type {name} in the library");
        }
    }
}
