//! Opening a headless wgpu device, shared by every GPU stage of tessd (the stencil apply phase
//! here, the renderer of `tessd-render`), so that all of them pick adapters, raise limits and
//! report failures the same way.
//!
//! The backends are the platform's (core/gpu/Cargo.toml): Vulkan on Linux (which covers
//! lavapipe, Mesa's software driver, what CI runs on), DX12 and Vulkan on Windows, Metal on
//! macOS; a real GPU is preferred and a CPU adapter accepted, and the adapter is reported. wgpu's validation and out-of-memory errors
//! are caught with [`ErrorScopes`], so bad input gives an error, never wgpu's default panic.

use crate::GpuError;

/// A device and its queue, with what the adapter said about itself.
pub struct GpuContext {
    /// The adapter the device was opened on.
    pub adapter_info: wgpu::AdapterInfo,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl GpuContext {
    /// Opens a device labelled `label` on the best adapter of this build's backends: a
    /// discrete GPU, then an integrated one, a virtual one, any other, and last a CPU (fallback)
    /// adapter. An adapter that lists but refuses a device is passed over for the next one (under
    /// Wine, DX12 through vkd3d lists a GPU whose device cannot be opened, while Vulkan over
    /// lavapipe works). Limits are wgpu's defaults except buffer sizes and the 2D texture size,
    /// raised to the adapter's so large meshes and large images fit.
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when there is no adapter at all (the message says which packages
    /// give the software one), [`GpuError::DeviceRequest`] (the best adapter's) when every
    /// adapter refuses the device.
    pub fn open(label: &str) -> Result<Self, GpuError> {
        pollster::block_on(Self::open_async(label))
    }

    /// Opens a device that can present to `window` (the interactive viewer, `tessd view`), and
    /// the window's surface: the same adapter preference and limits as [`open`](Self::open),
    /// among the adapters that support the surface. Unlike [`open`](Self::open)'s instance,
    /// this one keeps the window-system extensions: a window needs them. The surface's formats
    /// on the chosen adapter come with it.
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when no adapter can draw on the window (the message says
    /// which packages give the software one), [`GpuError::DeviceRequest`] when every such
    /// adapter refuses a device, [`GpuError::Wgpu`] when the surface cannot be created.
    #[allow(clippy::type_complexity)]
    pub fn open_for_window<W>(
        label: &str,
        window: W,
    ) -> Result<(Self, wgpu::Surface<'static>, Vec<wgpu::TextureFormat>), GpuError>
    where
        W: wgpu::WindowHandle + wgpu::wgt::WgpuHasDisplayHandle + Clone + 'static,
    {
        let instance = window_instance(&window);
        let surface = instance
            .create_surface(window)
            .map_err(|e| GpuError::Wgpu(format!("cannot draw on the window: {e}")))?;
        pollster::block_on(async {
            let adapters: Vec<wgpu::Adapter> = instance
                .enumerate_adapters(wgpu::Backends::all())
                .await
                .into_iter()
                .filter(|a| a.is_surface_supported(&surface))
                .collect();
            if adapters.is_empty() {
                return Err(GpuError::NoAdapter(
                    "no adapter can draw on this window".to_string(),
                ));
            }
            let (context, formats) =
                Self::open_best(adapters, label, |a| surface.get_capabilities(a).formats).await?;
            Ok((context, surface, formats))
        })
    }

    /// [`open`](Self::open), as a future (for callers already inside one).
    ///
    /// # Errors
    /// As [`open`](Self::open).
    pub async fn open_async(label: &str) -> Result<Self, GpuError> {
        let instance = headless_instance()?;
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        if adapters.is_empty() {
            // wgpu's own request says why there is none.
            let adapter = instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    force_fallback_adapter: false,
                    compatible_surface: None,
                    apply_limit_buckets: false,
                })
                .await
                .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
            adapters.push(adapter);
        }
        Ok(Self::open_best(adapters, label, |_| ()).await?.0)
    }

    /// Opens a device on the first of `adapters` (at least one) that gives one, in the order of
    /// [`preference`], with what `about` says of that adapter; the first adapter's error when
    /// none does.
    async fn open_best<T>(
        mut adapters: Vec<wgpu::Adapter>,
        label: &str,
        about: impl Fn(&wgpu::Adapter) -> T,
    ) -> Result<(Self, T), GpuError> {
        // Stable: among adapters of one kind, wgpu's order (the backends' order) stands.
        adapters.sort_by_key(|a| preference(a.get_info().device_type));
        let mut first_error = None;
        for adapter in adapters {
            let about = about(&adapter);
            match Self::open_on(adapter, label).await {
                Ok(context) => return Ok((context, about)),
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        Err(first_error.expect("at least one adapter was tried"))
    }

    /// Opens the device on `adapter`.
    async fn open_on(adapter: wgpu::Adapter, label: &str) -> Result<Self, GpuError> {
        let adapter_info = adapter.get_info();
        let adapter_limits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_texture_dimension_2d: adapter_limits.max_texture_dimension_2d,
            // The renderer's B-Rep passes bind a part's six surface and trim buffers beside
            // the frame's own (up to 14 in one stage); every Vulkan driver offers far more.
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage
                .clamp(8, 16),
            ..wgpu::Limits::default()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some(label),
                required_limits,
                // Early depth tests forced on fragment shaders with side effects, where the
                // adapter has them: object-space crack filling relies on the depth mask
                // culling fragments before they run (paper 001 §3.4.1).
                required_features: adapter.features() & wgpu::Features::SHADER_EARLY_DEPTH_TEST,
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::DeviceRequest {
                adapter: describe(&adapter_info),
                source,
            })?;
        Ok(Self {
            adapter_info,
            device,
            queue,
        })
    }

    /// The adapter as one line: name, backend, device type and driver (lavapipe shows as
    /// `llvmpipe ... (Vulkan, Cpu; driver llvmpipe ...)`), for logs and test output.
    pub fn describe(&self) -> String {
        describe(&self.adapter_info)
    }
}

/// The order in which [`GpuContext::open`] tries adapters: real GPUs first, the CPU last.
fn preference(kind: wgpu::DeviceType) -> u8 {
    match kind {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The window-system surface extensions a headless instance leaves out (see
/// [`vulkan_without`]).
#[cfg(all(unix, not(target_vendor = "apple")))]
const WINDOW_SYSTEM_EXTENSIONS: [&std::ffi::CStr; 3] = [
    c"VK_KHR_wayland_surface",
    c"VK_KHR_xcb_surface",
    c"VK_KHR_xlib_surface",
];

/// A wgpu instance for offscreen work: the backends of this build (and `WGPU_BACKEND`,
/// `WGPU_VALIDATION`... from the environment). On Linux and the BSDs its Vulkan instance is
/// created without the window-system surface extensions ([`vulkan_without`]);
/// elsewhere (DX12 and Vulkan on Windows, Metal on macOS) wgpu creates it as it is, and the
/// adapter request picks among all backends.
///
/// # Errors
/// [`GpuError::NoAdapter`] when Vulkan is the only backend and cannot be initialised (no
/// loader: `libvulkan1` missing).
fn headless_instance() -> Result<wgpu::Instance, GpuError> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Instance::enabled_backend_features();
    let desc = desc.with_env();
    #[cfg(all(unix, not(target_vendor = "apple")))]
    if desc.backends.contains(wgpu::Backends::VULKAN) {
        return vulkan_without(desc, &WINDOW_SYSTEM_EXTENSIONS, None);
    }
    Ok(wgpu::Instance::new(desc))
}

/// A wgpu instance that can draw on `window`. On Linux and the BSDs outside a Wayland session
/// (no `WAYLAND_DISPLAY`: X11, or Xvfb), its Vulkan instance leaves out only the Wayland surface
/// extension, for the reason [`vulkan_without`] gives; a Wayland session keeps it.
fn window_instance<W>(window: &W) -> wgpu::Instance
where
    W: wgpu::wgt::WgpuHasDisplayHandle + Clone,
{
    let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(window.clone()));
    desc.backends = wgpu::Instance::enabled_backend_features();
    let desc = desc.with_env();
    #[cfg(all(unix, not(target_vendor = "apple")))]
    if desc.backends.contains(wgpu::Backends::VULKAN)
        && std::env::var_os("WAYLAND_DISPLAY").is_none_or(|v| v.is_empty())
    {
        let display = window.display_handle().ok();
        let plain = wgpu::InstanceDescriptor {
            backends: desc.backends,
            flags: desc.flags,
            memory_budget_thresholds: desc.memory_budget_thresholds,
            backend_options: desc.backend_options.clone(),
            display: None,
        };
        if let Ok(instance) = vulkan_without(plain, &[c"VK_KHR_wayland_surface"], display) {
            return instance;
        }
    }
    wgpu::Instance::new(desc)
}

/// The Vulkan instance of `desc`, created through wgpu-hal without the surface extensions
/// `leave_out` (for offscreen work, all the window systems': Wayland, XCB, Xlib), with the
/// display `display` (a window's).
///
/// wgpu enables every surface extension the loader offers, and Mesa's device-selection layer
/// (an implicit layer of `mesa-vulkan-drivers`) takes `VK_KHR_wayland_surface` as a sign that
/// the program draws on Wayland: it connects to the compositor to find the default GPU, and on a
/// machine without a session (ssh, cron, CI, render nodes: no `XDG_RUNTIME_DIR`) libwayland
/// prints `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` on stderr at every
/// adapter enumeration (issue 32). Offscreen work never presents, so it never needs them, and a
/// window on X11 needs only X's: wgpu-hal checks that an extension was enabled before creating
/// a surface with it.
///
/// Should Vulkan fail while other backends are enabled (`WGPU_BACKEND`), those are used.
///
/// # Errors
/// As [`headless_instance`].
#[cfg(all(unix, not(target_vendor = "apple")))]
fn vulkan_without(
    desc: wgpu::InstanceDescriptor,
    leave_out: &'static [&'static std::ffi::CStr],
    display: Option<wgpu::rwh::DisplayHandle<'_>>,
) -> Result<wgpu::Instance, GpuError> {
    let hal_desc = wgpu::hal::InstanceDescriptor {
        name: "tessd",
        flags: desc.flags,
        memory_budget_thresholds: desc.memory_budget_thresholds,
        backend_options: desc.backend_options.clone(),
        telemetry: None,
        display,
    };
    let leave_out_window_systems: Box<wgpu::hal::vulkan::CreateInstanceCallback> =
        Box::new(move |args| {
            args.extensions.retain(|e| !leave_out.contains(e));
        });
    // SAFETY: the descriptor is wgpu's own, from the environment, and `display` (a window's)
    // outlives the instance. The callback removes only surface extensions, which wgpu-hal looks
    // up before creating a surface (it then refuses the surface) and which tessd never creates
    // a surface with; nothing else about the instance changes.
    let hal = unsafe {
        wgpu::hal::vulkan::Instance::init_with_callback(&hal_desc, Some(leave_out_window_systems))
    };
    match hal {
        // SAFETY: `hal` is a freshly created, valid Vulkan instance that wgpu now owns.
        Ok(hal) => Ok(unsafe { wgpu::Instance::from_hal::<wgpu::hal::api::Vulkan>(hal) }),
        Err(e) if desc.backends == wgpu::Backends::VULKAN => {
            let mut reason = format!("Vulkan: {e}");
            if let Some(source) = std::error::Error::source(&e) {
                reason.push_str(&format!(": {source}"));
            }
            Err(GpuError::NoAdapter(reason))
        }
        Err(_) => {
            let mut others = desc;
            others.backends.remove(wgpu::Backends::VULKAN);
            Ok(wgpu::Instance::new(others))
        }
    }
}

/// `info` as one line: name, backend, device type and driver.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({:?}, {:?}; driver {} {})",
        info.name, info.backend, info.device_type, info.driver, info.driver_info
    )
}

/// Validation and out-of-memory error scopes around a group of wgpu calls, so that an error
/// becomes a [`GpuError`] instead of reaching wgpu's default handler, which panics.
///
/// Fields drop in declaration order, and scopes must pop innermost first: `validation` (pushed
/// last) comes first.
pub struct ErrorScopes {
    validation: wgpu::ErrorScopeGuard,
    oom: wgpu::ErrorScopeGuard,
}

impl ErrorScopes {
    /// Pushes an out-of-memory scope, then a validation scope.
    pub fn push(device: &wgpu::Device) -> Self {
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        Self { validation, oom }
    }

    /// Pops both scopes (inner first).
    ///
    /// # Errors
    /// [`GpuError::Wgpu`] with the first error either caught.
    pub async fn pop(self) -> Result<(), GpuError> {
        let validation = self.validation.pop().await;
        let oom = self.oom.pop().await;
        match validation.or(oom) {
            Some(e) => Err(GpuError::Wgpu(e.to_string())),
            None => Ok(()),
        }
    }

    /// [`pop`](Self::pop), blocking.
    ///
    /// # Errors
    /// As [`pop`](Self::pop).
    pub fn pop_blocking(self) -> Result<(), GpuError> {
        pollster::block_on(self.pop())
    }
}
