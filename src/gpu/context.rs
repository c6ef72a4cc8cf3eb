//! Vulkan instance, device choice, compute queue and memory allocator.
//! Validation layers are enabled when `VKPT_VALIDATION=1`; every message they
//! print is counted so tests can fail on any.

use anyhow::{Context as _, anyhow, bail};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{CStr, c_void};
use std::mem::ManuallyDrop;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Validation messages (warnings and errors) seen by this process.
pub static VALIDATION_MESSAGES: AtomicU64 = AtomicU64::new(0);

/// Which Vulkan device to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VulkanDevice {
    /// The best one: discrete > integrated > virtual GPU > CPU driver.
    Best,
    /// Any device that is not a CPU driver.
    Hardware,
    /// Mesa's lavapipe (a Vulkan driver running on the CPU).
    Lavapipe,
}

pub struct Context {
    _entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub physical_device: vk::PhysicalDevice,
    pub properties: vk::PhysicalDeviceProperties,
    /// `VkPhysicalDeviceIDProperties::driverUUID`: part of the pipeline cache key.
    pub driver_uuid: [u8; vk::UUID_SIZE],
    /// Compute kernels may use subgroup arithmetic (`subgroupAdd`), which
    /// `path_loop` needs and Vulkan 1.1 does not guarantee.
    pub subgroup_arithmetic: bool,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub timestamp_valid_bits: u32,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub validation: bool,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the loader passes a valid callback-data pointer for the call.
    let message = unsafe { data.as_ref() }
        .and_then(|d| unsafe { d.message_as_c_str() })
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    VALIDATION_MESSAGES.fetch_add(1, Ordering::Relaxed);
    eprintln!("vulkan validation ({severity:?}): {message}");
    vk::FALSE
}

fn device_type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 4,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 3,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 1,
        _ => 0,
    }
}

impl Context {
    /// `validation`: `None` follows `VKPT_VALIDATION`; `Some(b)` forces it
    /// (used only if the layer is installed).
    pub fn new(choice: VulkanDevice, force_validation: Option<bool>) -> anyhow::Result<Context> {
        // SAFETY: loading the system Vulkan loader; failure is reported.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            anyhow!(
                "Vulkan is not available ({e}). Install a Vulkan driver (Debian: \
                 `apt-get install mesa-vulkan-drivers libvulkan1`) or render with the CPU back end (DeviceChoice::Cpu)"
            )
        })?;

        let want_validation = force_validation
            .unwrap_or_else(|| std::env::var("VKPT_VALIDATION").is_ok_and(|v| v == "1"));
        // SAFETY: plain enumeration call.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
        let has_validation = layers
            .iter()
            .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        let validation = want_validation && has_validation;
        if want_validation && !has_validation && force_validation.is_none() {
            eprintln!(
                "warning: VKPT_VALIDATION=1 but {} is not installed (Debian: vulkan-validationlayers)",
                VALIDATION_LAYER.to_string_lossy()
            );
        }

        let app = vk::ApplicationInfo::default()
            .application_name(c"vkpt")
            .engine_name(c"vkpt")
            .api_version(vk::API_VERSION_1_2);
        let layer_names = if validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let extensions = if validation {
            vec![ash::ext::debug_utils::NAME.as_ptr()]
        } else {
            vec![]
        };
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extensions);
        // SAFETY: the create info and the arrays it points to outlive the call.
        let instance = unsafe { entry.create_instance(&info, None) }
            .context("creating the Vulkan instance")?;

        let debug = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback));
            // SAFETY: the instance was created with VK_EXT_debug_utils.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }?;
            Some((loader, messenger))
        } else {
            None
        };

        let picked = Self::pick_device(&instance, choice);
        let (physical_device, queue_family) = match picked {
            Ok(p) => p,
            Err(e) => {
                // SAFETY: nothing else uses the instance yet.
                unsafe {
                    if let Some((loader, messenger)) = &debug {
                        loader.destroy_debug_utils_messenger(*messenger, None);
                    }
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        // SAFETY: physical_device comes from this instance.
        let properties = unsafe { instance.get_physical_device_properties(physical_device) };
        let mut id = vk::PhysicalDeviceIDProperties::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut properties2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut id)
            .push_next(&mut subgroup);
        // SAFETY: as above; Vulkan 1.1 core, and the instance asks for 1.2.
        unsafe { instance.get_physical_device_properties2(physical_device, &mut properties2) };
        let driver_uuid = id.driver_uuid;
        let subgroup_arithmetic = subgroup
            .supported_operations
            .contains(vk::SubgroupFeatureFlags::ARITHMETIC)
            && subgroup
                .supported_stages
                .contains(vk::ShaderStageFlags::COMPUTE);
        // SAFETY: as above.
        let families =
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let timestamp_valid_bits = families[queue_family as usize].timestamp_valid_bits;

        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // pick_device checked that the device has it.
        let features = vk::PhysicalDeviceFeatures::default().shader_int64(true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&features);
        // SAFETY: valid physical device and create info.
        let device = unsafe { instance.create_device(physical_device, &info, None) }
            .context("creating the Vulkan device")?;
        // SAFETY: the family was requested with one queue.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .context("creating the GPU memory allocator")?;

        Ok(Context {
            _entry: entry,
            instance,
            debug,
            physical_device,
            properties,
            driver_uuid,
            subgroup_arithmetic,
            device,
            queue,
            queue_family,
            timestamp_valid_bits,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            validation,
        })
    }

    fn pick_device(
        instance: &ash::Instance,
        choice: VulkanDevice,
    ) -> anyhow::Result<(vk::PhysicalDevice, u32)> {
        // SAFETY: plain enumeration call.
        let devices = unsafe { instance.enumerate_physical_devices() }?;
        let mut seen = Vec::new();
        let mut best: Option<(u32, vk::PhysicalDevice, u32)> = None;
        for pd in devices {
            // SAFETY: pd comes from this instance.
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = props
                .device_name_as_c_str()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            seen.push(format!("{name} ({:?})", props.device_type));
            let is_cpu = props.device_type == vk::PhysicalDeviceType::CPU;
            let acceptable = match choice {
                VulkanDevice::Hardware => !is_cpu,
                VulkanDevice::Lavapipe => is_cpu,
                VulkanDevice::Best => true,
            };
            if !acceptable || vk::api_version_minor(props.api_version) < 2 {
                continue;
            }
            // The kernels store path state as 64-bit words (path_state.glsl).
            // SAFETY: pd comes from this instance.
            let features = unsafe { instance.get_physical_device_features(pd) };
            if features.shader_int64 == vk::FALSE {
                seen.push(format!("{name}: no shaderInt64"));
                continue;
            }
            // SAFETY: pd comes from this instance.
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            let Some(family) = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            else {
                continue;
            };
            let rank = device_type_rank(props.device_type);
            if best.is_none_or(|(r, _, _)| rank > r) {
                best = Some((rank, pd, family as u32));
            }
        }
        match best {
            Some((_, pd, family)) => Ok((pd, family)),
            None if seen.is_empty() => bail!(
                "no Vulkan device found. Install a driver (Debian: mesa-vulkan-drivers for \
                 lavapipe) or render with the CPU back end (DeviceChoice::Cpu)"
            ),
            None => bail!(
                "no Vulkan 1.2 device with a compute queue and shaderInt64 matches \
                 VulkanDevice::{choice:?}; found: {}",
                seen.join(", ")
            ),
        }
    }

    pub fn device_name(&self) -> String {
        self.properties
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|_| "unnamed Vulkan device".into())
    }

    pub fn is_cpu_device(&self) -> bool {
        self.properties.device_type == vk::PhysicalDeviceType::CPU
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: every object made from the device is destroyed by its owner
        // before the Context (the renderer drops its resources first).
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
