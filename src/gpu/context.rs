//! `Gpu`: the one owner of the Vulkan instance, device, queue, allocator and command pool.

use super::GpuError;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to set up the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Khronos validation layer + synchronization validation, messages collected in [`ValidationLog`].
    pub validation: bool,
    /// Index (as listed by `volcast devices`) or case-insensitive part of the device name.
    pub device: Option<String>,
    /// Instance extensions a window surface needs (from ash-window); empty for headless use.
    pub instance_extensions: Vec<&'static CStr>,
    /// Enable VK_KHR_swapchain on the device.
    pub swapchain: bool,
    /// How renderers on this GPU store volumes (`--texture`).
    pub texel_policy: super::TexelPolicy,
    /// The side of the bricks renderers on this GPU cut volumes into (`--brick-size`); None: one brick per volume
    /// where it fits the device's 3D limit (render/pool.rs).
    pub brick_side: Option<u32>,
}

/// One validation-layer message.
#[derive(Clone, Debug)]
pub struct ValidationMessage {
    pub severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    pub text: String,
}

/// Everything the validation layer said, plus resource leaks found at shutdown. Shared (`Arc`) so it can be
/// read after the `Gpu` is gone: the leak report arrives while the device is being destroyed.
#[derive(Default, Debug)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
    /// Print each message to stderr as it arrives.
    pub echo: bool,
}

impl ValidationLog {
    pub fn push(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, text: String) {
        if self.echo {
            eprintln!("[validation {}] {text}", severity_name(severity));
        }
        if let Ok(mut m) = self.messages.lock() {
            m.push(ValidationMessage { severity, text });
        }
    }

    /// Errors and warnings: what a test fails on.
    pub fn problems(&self) -> Vec<ValidationMessage> {
        let serious = vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING;
        self.messages
            .lock()
            .map(|m| m.iter().filter(|x| x.severity.intersects(serious)).cloned().collect())
            .unwrap_or_default()
    }

    pub fn error_count(&self) -> usize {
        self.messages
            .lock()
            .map(|m| {
                m.iter()
                    .filter(|x| x.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR))
                    .count()
            })
            .unwrap_or(0)
    }

    pub fn warning_count(&self) -> usize {
        self.messages
            .lock()
            .map(|m| {
                m.iter()
                    .filter(|x| x.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING))
                    .count()
            })
            .unwrap_or(0)
    }
}

fn severity_name(s: vk::DebugUtilsMessageSeverityFlagsEXT) -> &'static str {
    if s.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        "error"
    } else if s.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        "warning"
    } else {
        "info"
    }
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the ValidationLog inside an Arc that the Gpu keeps alive until after the messenger and
    // instance are destroyed; `data` and its strings are valid for the duration of the callback (spec).
    unsafe {
        if user.is_null() || data.is_null() {
            return vk::FALSE;
        }
        let log = &*(user as *const ValidationLog);
        let d = &*data;
        let text = if d.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(d.p_message).to_string_lossy().into_owned()
        };
        log.push(severity, text);
    }
    vk::FALSE
}

/// A physical device as `volcast devices` lists it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: u32,
    /// Why it can't be used, if it can't.
    pub unsuitable: Option<String>,
}

impl std::fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        };
        let v = self.api_version;
        write!(
            f,
            "{}: {} ({kind}, Vulkan {}.{}.{})",
            self.index,
            self.name,
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        )?;
        if let Some(why) = &self.unsuitable {
            write!(f, " — unusable: {why}")?;
        }
        Ok(())
    }
}

fn kind_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// The Vulkan objects every other part borrows. Field order is not drop order: see `Drop`.
pub struct Gpu {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub log: Arc<ValidationLog>,
    pub physical: vk::PhysicalDevice,
    pub properties: vk::PhysicalDeviceProperties,
    pub device_name: String,
    pub device: ash::Device,
    pub queue_family: u32,
    pub queue: vk::Queue,
    /// Shared with egui-ash-renderer in the viewer; always dropped before the device.
    pub allocator: Option<Arc<Mutex<Allocator>>>,
    pub command_pool: vk::CommandPool,
    /// Size of the largest device-local heap, the budget a volume is checked against.
    pub device_local_bytes: u64,
    /// From [`GpuOptions::texel_policy`]: the policy new renderers start with.
    pub texel_policy: super::TexelPolicy,
    /// From [`GpuOptions::brick_side`].
    pub brick_side: Option<u32>,
}

fn load_entry() -> Result<ash::Entry, GpuError> {
    // SAFETY: loading libvulkan runs its initialisers; the Khronos loader is designed to be loaded this way.
    unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoVulkan(format!("could not load the Vulkan loader ({e})")))
}

fn create_instance(
    entry: &ash::Entry,
    opts: &GpuOptions,
    log: &Arc<ValidationLog>,
) -> Result<
    (
        ash::Instance,
        Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    ),
    GpuError,
> {
    // SAFETY: plain query on a loaded entry.
    let version = unsafe { entry.try_enumerate_instance_version() }
        .map_err(|e| GpuError::vk("vkEnumerateInstanceVersion", e))?
        .unwrap_or(vk::API_VERSION_1_0);
    if version < vk::API_VERSION_1_3 {
        return Err(GpuError::NoVulkan(format!(
            "the Vulkan loader supports only {}.{}; volcast needs Vulkan 1.3",
            vk::api_version_major(version),
            vk::api_version_minor(version)
        )));
    }
    let mut layers: Vec<*const i8> = Vec::new();
    let mut extensions: Vec<*const i8> = opts.instance_extensions.iter().map(|e| e.as_ptr()).collect();
    if opts.validation {
        // SAFETY: plain query on a loaded entry.
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .map_err(|e| GpuError::vk("vkEnumerateInstanceLayerProperties", e))?;
        let found = available
            .iter()
            .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
        if !found {
            return Err(GpuError::NoValidationLayer);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
    }
    let app = vk::ApplicationInfo::default()
        .application_name(c"volcast")
        .engine_name(c"volcast")
        .api_version(vk::API_VERSION_1_3);
    let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut validation_features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
    let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(log) as *mut c_void);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if opts.validation {
        // Chained so that instance creation and destruction are validated too.
        info = info.push_next(&mut messenger_info).push_next(&mut validation_features);
    }
    // SAFETY: every pointer in `info` refers to locals that outlive the call.
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoVulkan("no Vulkan driver is installed".into()),
        e => GpuError::vk("vkCreateInstance", e),
    })?;
    let debug = if opts.validation {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        // SAFETY: the instance is live and `messenger_info` only points at the log, which outlives the messenger.
        match unsafe { loader.create_debug_utils_messenger(&messenger_info, None) } {
            Ok(m) => Some((loader, m)),
            Err(e) => {
                // SAFETY: nothing was created from this instance yet.
                unsafe { instance.destroy_instance(None) };
                return Err(GpuError::vk("vkCreateDebugUtilsMessengerEXT", e));
            }
        }
    } else {
        None
    };
    Ok((instance, debug))
}

fn describe_devices(instance: &ash::Instance, opts: &GpuOptions) -> Result<Vec<DeviceInfo>, GpuError> {
    // SAFETY: the instance is live.
    let physicals =
        unsafe { instance.enumerate_physical_devices() }.map_err(|e| GpuError::vk("vkEnumeratePhysicalDevices", e))?;
    Ok(physicals
        .iter()
        .enumerate()
        .map(|(index, &pd)| {
            // SAFETY: `pd` comes from this instance.
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = props
                .device_name_as_c_str()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            DeviceInfo {
                index,
                name,
                kind: props.device_type,
                api_version: props.api_version,
                unsuitable: unsuitable_reason(instance, pd, &props, opts),
            }
        })
        .collect())
}

fn unsuitable_reason(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
    opts: &GpuOptions,
) -> Option<String> {
    if props.api_version < vk::API_VERSION_1_3 {
        return Some("supports only Vulkan 1.2 or older".into());
    }
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
    // SAFETY: `pd` comes from this instance; the chain points at locals.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    if f13.dynamic_rendering == vk::FALSE || f13.synchronization2 == vk::FALSE {
        return Some("lacks dynamicRendering or synchronization2".into());
    }
    if graphics_queue_family(instance, pd).is_none() {
        return Some("has no graphics queue".into());
    }
    if opts.swapchain {
        // SAFETY: as above.
        let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
        if !exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(ash::khr::swapchain::NAME))
        {
            return Some("has no VK_KHR_swapchain".into());
        }
    }
    None
}

fn graphics_queue_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<u32> {
    // SAFETY: `pd` comes from this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        .map(|i| i as u32)
}

/// Picks by `--device` (index or name part), else discrete > integrated > virtual > CPU.
fn choose(devices: &[DeviceInfo], wanted: Option<&str>) -> Result<usize, GpuError> {
    let usable: Vec<&DeviceInfo> = devices.iter().filter(|d| d.unsuitable.is_none()).collect();
    let list = || devices.iter().map(|d| format!("\n  {d}")).collect::<String>();
    match wanted {
        Some(w) => {
            let hit = match w.parse::<usize>() {
                Ok(i) => devices.iter().find(|d| d.index == i),
                Err(_) => {
                    let w = w.to_lowercase();
                    devices.iter().find(|d| d.name.to_lowercase().contains(&w))
                }
            };
            match hit {
                Some(d) if d.unsuitable.is_none() => Ok(d.index),
                Some(d) => Err(GpuError::NoDevice(format!("device {d}"))),
                None => Err(GpuError::NoDevice(format!(
                    "no device matches --device {w}; devices:{}",
                    list()
                ))),
            }
        }
        None => usable
            .iter()
            .min_by_key(|d| (kind_rank(d.kind), d.index))
            .map(|d| d.index)
            .ok_or_else(|| GpuError::NoDevice(format!("no Vulkan 1.3 device with dynamic rendering{}", list()))),
    }
}

/// The device volcast takes when `--device` does not say (see [`list_devices`]), if any is usable.
pub fn default_device(devices: &[DeviceInfo]) -> Option<usize> {
    choose(devices, None).ok()
}

/// Lists the physical devices (for `volcast devices`).
pub fn list_devices() -> Result<Vec<DeviceInfo>, GpuError> {
    let entry = load_entry()?;
    let log = Arc::new(ValidationLog::default());
    let opts = GpuOptions::default();
    let (instance, _) = create_instance(&entry, &opts, &log)?;
    let devices = describe_devices(&instance, &opts);
    // SAFETY: nothing else was created from this instance.
    unsafe { instance.destroy_instance(None) };
    devices
}

impl Gpu {
    pub fn new(opts: &GpuOptions) -> Result<Gpu, GpuError> {
        let entry = load_entry()?;
        let log = Arc::new(ValidationLog {
            echo: true,
            ..Default::default()
        });
        let (instance, debug) = create_instance(&entry, opts, &log)?;
        // From here on, a failure must tear down what exists: build the rest in a helper and clean up on error.
        match Self::create_device(&instance, opts) {
            Ok((physical, properties, device_name, device, queue_family, device_local_bytes)) => {
                let gpu = Gpu {
                    entry,
                    instance,
                    debug,
                    log,
                    physical,
                    properties,
                    device_name,
                    device,
                    queue_family,
                    queue: vk::Queue::null(),
                    allocator: None,
                    command_pool: vk::CommandPool::null(),
                    device_local_bytes,
                    texel_policy: opts.texel_policy,
                    brick_side: opts.brick_side,
                };
                gpu.finish()
            }
            Err(e) => {
                // SAFETY: only the messenger and instance exist; destroy in reverse order.
                unsafe {
                    if let Some((loader, m)) = &debug {
                        loader.destroy_debug_utils_messenger(*m, None);
                    }
                    instance.destroy_instance(None);
                }
                Err(e)
            }
        }
    }

    #[allow(clippy::type_complexity)]
    fn create_device(
        instance: &ash::Instance,
        opts: &GpuOptions,
    ) -> Result<
        (
            vk::PhysicalDevice,
            vk::PhysicalDeviceProperties,
            String,
            ash::Device,
            u32,
            u64,
        ),
        GpuError,
    > {
        let devices = describe_devices(instance, opts)?;
        if devices.is_empty() {
            return Err(GpuError::NoDevice("the Vulkan loader found no physical device".into()));
        }
        let index = choose(&devices, opts.device.as_deref())?;
        // SAFETY: the instance is live.
        let physical = unsafe { instance.enumerate_physical_devices() }
            .map_err(|e| GpuError::vk("vkEnumeratePhysicalDevices", e))?[index];
        // SAFETY: `physical` comes from this instance.
        let properties = unsafe { instance.get_physical_device_properties(physical) };
        // SAFETY: as above.
        let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
        let device_local_bytes = memory.memory_heaps[..memory.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        let queue_family =
            graphics_queue_family(instance, physical).ok_or_else(|| GpuError::NoDevice("no graphics queue".into()))?;
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut extensions: Vec<*const i8> = Vec::new();
        if opts.swapchain {
            extensions.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&extensions)
            .push_next(&mut f13);
        // SAFETY: `physical` supports these features and extensions (checked in unsuitable_reason).
        let device =
            unsafe { instance.create_device(physical, &info, None) }.map_err(|e| GpuError::vk("vkCreateDevice", e))?;
        let device_name = devices[index].name.clone();
        Ok((
            physical,
            properties,
            device_name,
            device,
            queue_family,
            device_local_bytes,
        ))
    }

    fn finish(mut self) -> Result<Gpu, GpuError> {
        // SAFETY: the device was created with one queue in `queue_family`.
        self.queue = unsafe { self.device.get_device_queue(self.queue_family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is live. On error `self` drops, which cleans up what exists.
        self.command_pool = unsafe { self.device.create_command_pool(&pool_info, None) }
            .map_err(|e| GpuError::vk("vkCreateCommandPool", e))?;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: self.instance.clone(),
            device: self.device.clone(),
            physical_device: self.physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(GpuError::Alloc)?;
        self.allocator = Some(Arc::new(Mutex::new(allocator)));
        Ok(self)
    }

    /// The allocator, locked. Poisoning (a panic while allocating) is reported as an error, not a second panic.
    pub fn allocator(&self) -> Result<std::sync::MutexGuard<'_, Allocator>, GpuError> {
        self.allocator
            .as_ref()
            .ok_or(GpuError::Lost("allocator already released"))?
            .lock()
            .map_err(|_| GpuError::Lost("allocator mutex poisoned"))
    }

    /// Records commands with `record`, submits them and waits for them to finish.
    pub fn submit_and_wait<F>(&self, record: F) -> Result<(), GpuError>
    where
        F: FnOnce(vk::CommandBuffer),
    {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device and is only used from this thread.
        let cb = unsafe { self.device.allocate_command_buffers(&alloc) }
            .map_err(|e| GpuError::vk("vkAllocateCommandBuffers", e))?[0];
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            // SAFETY: `cb` is a fresh primary command buffer.
            unsafe { self.device.begin_command_buffer(cb, &begin) }
                .map_err(|e| GpuError::vk("vkBeginCommandBuffer", e))?;
            record(cb);
            // SAFETY: `cb` is recording.
            unsafe { self.device.end_command_buffer(cb) }.map_err(|e| GpuError::vk("vkEndCommandBuffer", e))?;
            // SAFETY: the device is live.
            let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }
                .map_err(|e| GpuError::vk("vkCreateFence", e))?;
            let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cbs)];
            // SAFETY: `cb` is executable; the fence is unsignalled; we wait before anything is freed.
            let r = unsafe { self.device.queue_submit2(self.queue, &submit, fence) }
                .map_err(|e| GpuError::vk("vkQueueSubmit2", e))
                .and_then(|_| {
                    // SAFETY: the fence was just submitted.
                    unsafe { self.device.wait_for_fences(&[fence], true, u64::MAX) }
                        .map_err(|e| GpuError::vk("vkWaitForFences", e))
                });
            // SAFETY: the fence is no longer in use (waited, or the submit failed).
            unsafe { self.device.destroy_fence(fence, None) };
            r
        })();
        // SAFETY: the work is finished (or never started), so the command buffer is not in use.
        unsafe { self.device.free_command_buffers(self.command_pool, &[cb]) };
        result
    }

    /// Objects a test asserts are absent: validation errors and warnings so far.
    pub fn validation_problems(&self) -> Vec<ValidationMessage> {
        self.log.problems()
    }

    pub fn validation_enabled(&self) -> bool {
        self.debug.is_some()
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: teardown in reverse creation order after the device is idle; every child object was destroyed
        // by its owner's `destroy(self, &Gpu)` before the Gpu itself is dropped.
        unsafe {
            let _ = self.device.device_wait_idle();
            if let Some(allocator) = self.allocator.take() {
                match Arc::try_unwrap(allocator) {
                    Ok(mutex) => {
                        if let Ok(a) = mutex.lock() {
                            let report = a.generate_report();
                            for leaked in &report.allocations {
                                self.log.push(
                                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                                    format!("leaked GPU allocation '{}' ({} bytes)", leaked.name, leaked.size),
                                );
                            }
                        }
                        drop(mutex);
                    }
                    Err(_) => self.log.push(
                        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                        "allocator still shared at shutdown (a renderer outlived the Gpu)".into(),
                    ),
                }
            }
            if self.command_pool != vk::CommandPool::null() {
                self.device.destroy_command_pool(self.command_pool, None);
            }
            self.device.destroy_device(None);
            if let Some((loader, m)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
