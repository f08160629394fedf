//! The wgpu device a renderer draws with: adapter, device, queue (headless, or on an adapter
//! chosen for a window).

use crate::error::{Error, Result};

/// The wgpu device and what it runs on.
pub struct GpuContext {
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, backend, device type, driver.
    pub info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// Opens the default adapter without a window (backends from `WGPU_BACKEND` if set).
    /// Errors name what is missing (e.g. Mesa's lavapipe/llvmpipe drivers on a machine without GPU).
    pub fn new() -> Result<GpuContext> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| {
            Error::Gpu(format!(
                "no graphics adapter ({e}); without a GPU install Mesa's software drivers: \
                 apt-get install mesa-vulkan-drivers libegl1 libegl-mesa0 libgl1-mesa-dri"
            ))
        })?;
        Self::from_adapter(adapter)
    }

    /// Opens a device on `adapter` (e.g. one chosen for a window surface with
    /// `compatible_surface`); errors name the adapter.
    pub fn from_adapter(adapter: wgpu::Adapter) -> Result<GpuContext> {
        let info = adapter.get_info();
        let limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("cliffmap"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| {
            Error::Gpu(format!(
                "cannot open device on {} ({:?}): {e}",
                info.name, info.backend
            ))
        })?;
        Ok(GpuContext {
            adapter,
            device,
            queue,
            info,
        })
    }

    /// "name (backend, device type)" for reports.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }
}
