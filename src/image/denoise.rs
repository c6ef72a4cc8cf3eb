//! Denoising with Intel Open Image Denoise (OIDN) 2.x, its "RT" filter for
//! HDR path-traced images.
//!
//! OIDN is not a build dependency: vkpt builds and renders without it and
//! loads `libOpenImageDenoise.so.2` at run time (dlopen) only when asked to
//! denoise. It looks, in this order, at
//!
//! 1. `$VKPT_OIDN_LIB`, a path to the library (when set, only there);
//! 2. the README's install location, a Python venv at
//!    `~/.local/share/vkpt/oidn` holding PyPI's `pyoidn` wheel, which ships
//!    the library with its CPU device (`lib/python3*/site-packages/pyoidn/oidn/lib/`);
//! 3. the system loader's path (`LD_LIBRARY_PATH`, `ldconfig`), for an OIDN
//!    built or packaged elsewhere.
//!
//! Only the C functions called here are declared, with the signatures of
//! OIDN 2.x's `include/OpenImageDenoise/oidn.h` (`oidnSetFilterBool` and
//! friends are 2.x names: a 1.x library is refused for lacking them).
//! OIDN reports errors per thread: every call below and its check run on the
//! caller's thread.
//!
//! A denoised image is biased (it is the network's estimate, not the mean of
//! the samples): measure and compare raw renders, never denoised ones.

use anyhow::{Result, anyhow, bail, ensure};
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Environment variable naming the library file, overriding the search.
pub const LIBRARY_ENV: &str = "VKPT_OIDN_LIB";
/// The library's soname (OIDN 2.x).
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";
/// The venv the README's set-up command creates, relative to `$HOME`.
pub const INSTALL_DIR: &str = ".local/share/vkpt/oidn";
/// The command that installs OIDN where vkpt looks (Debian: needs the
/// `python3-venv` package). `--no-deps`: vkpt loads only the C library, not
/// the Python binding's numpy and cffi.
pub const INSTALL_COMMAND: &str = "python3 -m venv ~/.local/share/vkpt/oidn && \
                                   ~/.local/share/vkpt/oidn/bin/pip install --no-deps pyoidn";

// oidn.h enum values used here (C enums: passed as int).
const OIDN_DEVICE_TYPE_DEFAULT: c_int = 0;
const OIDN_ERROR_NONE: c_int = 0;
const OIDN_FORMAT_FLOAT3: c_int = 3;

type Handle = *mut c_void;

// The C declarations (oidn.h, 2.x) of the functions called, one alias each;
// OIDNDevice, OIDNBuffer and OIDNFilter are opaque pointers (`Handle`).
/// `OIDNDevice oidnNewDevice(OIDNDeviceType type)`
type NewDeviceFn = unsafe extern "C" fn(c_int) -> Handle;
/// `void oidnCommitDevice(OIDNDevice)`, `oidnReleaseDevice`,
/// `oidnReleaseBuffer`, `oidnCommitFilter`, `oidnExecuteFilter`,
/// `oidnReleaseFilter`: one handle in, nothing out.
type HandleFn = unsafe extern "C" fn(Handle);
/// `OIDNError oidnGetDeviceError(OIDNDevice device, const char** outMessage)`
type GetDeviceErrorFn = unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int;
/// `int oidnGetDeviceInt(OIDNDevice device, const char* name)`
type GetDeviceIntFn = unsafe extern "C" fn(Handle, *const c_char) -> c_int;
/// `OIDNBuffer oidnNewBuffer(OIDNDevice device, size_t byteSize)`
type NewBufferFn = unsafe extern "C" fn(Handle, usize) -> Handle;
/// `void oidnWriteBuffer(OIDNBuffer buffer, size_t byteOffset, size_t byteSize,
/// const void* srcHostPtr)`
type WriteBufferFn = unsafe extern "C" fn(Handle, usize, usize, *const c_void);
/// `void oidnReadBuffer(OIDNBuffer buffer, size_t byteOffset, size_t byteSize,
/// void* dstHostPtr)`
type ReadBufferFn = unsafe extern "C" fn(Handle, usize, usize, *mut c_void);
/// `OIDNFilter oidnNewFilter(OIDNDevice device, const char* type)`
type NewFilterFn = unsafe extern "C" fn(Handle, *const c_char) -> Handle;
/// `void oidnSetFilterImage(OIDNFilter filter, const char* name, OIDNBuffer
/// buffer, OIDNFormat format, size_t width, size_t height, size_t byteOffset,
/// size_t pixelByteStride, size_t rowByteStride)`
type SetFilterImageFn =
    unsafe extern "C" fn(Handle, *const c_char, Handle, c_int, usize, usize, usize, usize, usize);
/// `void oidnSetFilterBool(OIDNFilter filter, const char* name, bool value)`
type SetFilterBoolFn = unsafe extern "C" fn(Handle, *const c_char, bool);

/// The OIDN 2.x C functions vkpt calls, resolved from the loaded library.
struct Api {
    path: String,
    new_device: NewDeviceFn,
    commit_device: HandleFn,
    release_device: HandleFn,
    get_device_error: GetDeviceErrorFn,
    get_device_int: GetDeviceIntFn,
    new_buffer: NewBufferFn,
    write_buffer: WriteBufferFn,
    read_buffer: ReadBufferFn,
    release_buffer: HandleFn,
    new_filter: NewFilterFn,
    set_filter_image: SetFilterImageFn,
    set_filter_bool: SetFilterBoolFn,
    commit_filter: HandleFn,
    execute_filter: HandleFn,
    release_filter: HandleFn,
}

/// The text of `dlerror()`, or `fallback` when there is none.
fn dl_error(fallback: &str) -> String {
    // SAFETY: dlerror returns NULL or a NUL-terminated string valid until the
    // next dl* call on this thread; it is copied at once.
    let message = unsafe { libc::dlerror() };
    if message.is_null() {
        fallback.to_string()
    } else {
        // SAFETY: non-null, NUL-terminated (above).
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    }
}

/// Opens `path` (a file, or a bare soname for the loader's search) and
/// resolves the functions. A library found wanting is closed again; OIDN
/// stays loaded for the process's life (its worker threads must never
/// outlive its code).
fn open(path: &str) -> Result<Api, String> {
    let c_path = CString::new(path).map_err(|_| "the path contains a NUL byte".to_string())?;
    // SAFETY: c_path is NUL-terminated; dlopen runs the library's
    // initializers, which is what loading OIDN means.
    let handle = unsafe { libc::dlopen(c_path.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
    if handle.is_null() {
        return Err(dl_error("dlopen failed"));
    }
    let symbol = |name: &str| -> Result<*mut c_void, String> {
        let c_name = CString::new(name).expect("symbol names have no NUL");
        // SAFETY: handle is a live dlopen handle, c_name NUL-terminated.
        let f = unsafe { libc::dlsym(handle, c_name.as_ptr()) };
        if f.is_null() {
            Err(format!(
                "{path} has no {name}: not Open Image Denoise 2.x ({})",
                dl_error("symbol not found")
            ))
        } else {
            Ok(f)
        }
    };
    macro_rules! function {
        ($name:literal, $type:ty) => {
            // SAFETY: the symbol is the OIDN 2.x function of that name, whose
            // C declaration (oidn.h) the alias spells out; a function pointer
            // and a data pointer have the same size on Linux.
            unsafe { std::mem::transmute::<*mut c_void, $type>(symbol($name)?) }
        };
    }
    let api = || -> Result<Api, String> {
        Ok(Api {
            path: path.to_string(),
            new_device: function!("oidnNewDevice", NewDeviceFn),
            commit_device: function!("oidnCommitDevice", HandleFn),
            release_device: function!("oidnReleaseDevice", HandleFn),
            get_device_error: function!("oidnGetDeviceError", GetDeviceErrorFn),
            get_device_int: function!("oidnGetDeviceInt", GetDeviceIntFn),
            new_buffer: function!("oidnNewBuffer", NewBufferFn),
            write_buffer: function!("oidnWriteBuffer", WriteBufferFn),
            read_buffer: function!("oidnReadBuffer", ReadBufferFn),
            release_buffer: function!("oidnReleaseBuffer", HandleFn),
            new_filter: function!("oidnNewFilter", NewFilterFn),
            set_filter_image: function!("oidnSetFilterImage", SetFilterImageFn),
            set_filter_bool: function!("oidnSetFilterBool", SetFilterBoolFn),
            commit_filter: function!("oidnCommitFilter", HandleFn),
            execute_filter: function!("oidnExecuteFilter", HandleFn),
            release_filter: function!("oidnReleaseFilter", HandleFn),
        })
    };
    api().inspect_err(|_| {
        // SAFETY: a live handle none of whose functions was kept.
        unsafe { libc::dlclose(handle) };
    })
}

/// The library in the README's venv under `home`, when it is there (the
/// newest Python's, should the venv have been remade with another).
fn installed_library(home: &Path) -> Option<PathBuf> {
    let lib = home.join(INSTALL_DIR).join("lib");
    let mut pythons: Vec<PathBuf> = std::fs::read_dir(&lib)
        .ok()?
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("python3"))
        .map(|e| e.path())
        .collect();
    pythons.sort();
    pythons
        .into_iter()
        .rev()
        .map(|p| p.join("site-packages/pyoidn/oidn/lib").join(LIBRARY_NAME))
        .find(|p| p.is_file())
}

/// How to get the library, for the end of an error line.
fn install_hint() -> String {
    format!("install it with `{INSTALL_COMMAND}` or set {LIBRARY_ENV} to its {LIBRARY_NAME}")
}

/// Finds and loads the library (see the module doc for where it looks).
fn load() -> Result<Api, String> {
    if let Some(path) = std::env::var_os(LIBRARY_ENV).filter(|v| !v.is_empty()) {
        // dlopen reads a name without a slash as a soname to search for: an
        // existing file relative to the working directory is made absolute.
        let file = Path::new(&path);
        let target = match std::path::absolute(file) {
            Ok(absolute) if file.is_file() => absolute.to_string_lossy().into_owned(),
            _ => path.to_string_lossy().into_owned(),
        };
        let path = path.to_string_lossy();
        return open(&target).map_err(|e| {
            format!(
                "cannot load Open Image Denoise from {LIBRARY_ENV}={path}: {e}; {}",
                install_hint()
            )
        });
    }
    let home = std::env::var_os("HOME").filter(|h| !h.is_empty());
    if let Some(path) = home.and_then(|h| installed_library(Path::new(&h))) {
        let path = path.to_string_lossy().into_owned();
        return open(&path).map_err(|e| {
            format!(
                "cannot load Open Image Denoise from {path}: {e}; reinstall it with `{INSTALL_COMMAND}`"
            )
        });
    }
    open(LIBRARY_NAME).map_err(|_| {
        format!(
            "Open Image Denoise 2.x not found ({LIBRARY_ENV} is not set, ~/{INSTALL_DIR} has no \
             pyoidn, and {LIBRARY_NAME} is not on the library path); {}",
            install_hint()
        )
    })
}

/// The library, loaded once per process (the environment is read then).
fn api() -> Result<&'static Api, String> {
    static API: OnceLock<Result<Api, String>> = OnceLock::new();
    API.get_or_init(load).as_ref().map_err(Clone::clone)
}

/// An OIDN device; its release frees what was made on it.
struct Device {
    api: &'static Api,
    raw: Handle,
}

impl Device {
    /// The default device (OIDN picks a supported GPU, else the CPU).
    fn new(api: &'static Api) -> Result<Device> {
        // SAFETY: a plain call; a NULL result is checked below.
        let raw = unsafe { (api.new_device)(OIDN_DEVICE_TYPE_DEFAULT) };
        if raw.is_null() {
            // Creation errors are stored for the NULL device.
            let message = error_message(api, std::ptr::null_mut())
                .unwrap_or_else(|| "no reason given".to_string());
            bail!(
                "Open Image Denoise ({}): oidnNewDevice failed: {message}",
                api.path
            );
        }
        let device = Device { api, raw };
        // SAFETY: raw is a live device.
        unsafe { (api.commit_device)(raw) };
        device.check("oidnCommitDevice")?;
        Ok(device)
    }

    /// The library's version, e.g. 20501 for 2.5.1.
    fn version(&self) -> Result<i32> {
        let name = c"version";
        // SAFETY: live device, NUL-terminated name.
        let v = unsafe { (self.api.get_device_int)(self.raw, name.as_ptr()) };
        self.check("oidnGetDeviceInt(version)")?;
        Ok(v)
    }

    /// Fails with OIDN's message when the last calls left an error.
    fn check(&self, what: &str) -> Result<()> {
        match error_message(self.api, self.raw) {
            None => Ok(()),
            Some(message) => bail!(
                "Open Image Denoise ({}): {what} failed: {message}",
                self.api.path
            ),
        }
    }

    /// A buffer holding a copy of `pixels`.
    fn buffer_from(&self, pixels: &[[f32; 3]], what: &str) -> Result<Buffer<'_>> {
        let buffer = self.buffer(pixels.len(), what)?;
        let bytes = std::mem::size_of_val(pixels);
        // SAFETY: the buffer holds `bytes` bytes (made from the same length),
        // and `pixels` is that many readable bytes.
        unsafe { (self.api.write_buffer)(buffer.raw, 0, bytes, pixels.as_ptr().cast()) };
        self.check(&format!("oidnWriteBuffer({what})"))?;
        Ok(buffer)
    }

    /// An uninitialized buffer of `pixels` RGB float pixels.
    fn buffer(&self, pixels: usize, what: &str) -> Result<Buffer<'_>> {
        let bytes = pixels * std::mem::size_of::<[f32; 3]>();
        // SAFETY: live device; a NULL result is checked.
        let raw = unsafe { (self.api.new_buffer)(self.raw, bytes) };
        self.check(&format!("oidnNewBuffer({what}, {bytes} bytes)"))?;
        ensure!(!raw.is_null(), "oidnNewBuffer({what}) returned no buffer");
        Ok(Buffer {
            device: self,
            raw,
            pixels,
        })
    }

    /// A new "RT" filter, named `what` in errors.
    fn rt_filter(&self, what: &'static str) -> Result<Filter<'_>> {
        // SAFETY: live device, NUL-terminated type name.
        let raw = unsafe { (self.api.new_filter)(self.raw, c"RT".as_ptr()) };
        self.check(&format!("oidnNewFilter(RT) for the {what}"))?;
        ensure!(!raw.is_null(), "oidnNewFilter(RT) returned no filter");
        Ok(Filter {
            device: self,
            raw,
            what,
        })
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the device is live, and buffers and filters (which borrow
        // it) are gone.
        unsafe { (self.api.release_device)(self.raw) };
    }
}

/// The device's first unqueried error, cleared by asking (None: no error).
fn error_message(api: &Api, device: Handle) -> Option<String> {
    let mut message: *const c_char = std::ptr::null();
    // SAFETY: device is live or NULL (allowed: per-thread global errors);
    // message receives NULL or a NUL-terminated string valid until the next
    // OIDN call, copied at once.
    let code = unsafe { (api.get_device_error)(device, &mut message) };
    if code == OIDN_ERROR_NONE {
        return None;
    }
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: non-null and NUL-terminated (above).
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    let kind = match code {
        1 => "unknown error",
        2 => "invalid argument",
        3 => "invalid operation",
        4 => "out of memory",
        5 => "unsupported hardware",
        6 => "cancelled",
        _ => "error",
    };
    Some(format!("{text} ({kind}, code {code})"))
}

/// A buffer of RGB float pixels on the device.
struct Buffer<'d> {
    device: &'d Device,
    raw: Handle,
    pixels: usize,
}

impl Buffer<'_> {
    fn read(&self) -> Result<Vec<[f32; 3]>> {
        let mut pixels = vec![[0.0f32; 3]; self.pixels];
        let bytes = std::mem::size_of_val(pixels.as_slice());
        // SAFETY: the buffer and `pixels` both hold `bytes` bytes.
        unsafe { (self.device.api.read_buffer)(self.raw, 0, bytes, pixels.as_mut_ptr().cast()) };
        self.device.check("oidnReadBuffer(output)")?;
        Ok(pixels)
    }
}

impl Drop for Buffer<'_> {
    fn drop(&mut self) {
        // SAFETY: live buffer; filters that use it are released first
        // (declared later, dropped earlier) or keep their own reference.
        unsafe { (self.device.api.release_buffer)(self.raw) };
    }
}

/// An "RT" filter being set up and run.
struct Filter<'d> {
    device: &'d Device,
    raw: Handle,
    what: &'static str,
}

impl Filter<'_> {
    /// Binds `buffer` as the image `name` ("color", "albedo", "normal",
    /// "output"): tightly packed RGB float rows of `width` pixels.
    fn set_image(&self, name: &CStr, buffer: &Buffer, width: u32, height: u32) -> Result<()> {
        // SAFETY: live filter and buffer; the buffer holds width * height
        // pixels (checked by `denoise`); strides 0 mean tightly packed.
        unsafe {
            (self.device.api.set_filter_image)(
                self.raw,
                name.as_ptr(),
                buffer.raw,
                OIDN_FORMAT_FLOAT3,
                width as usize,
                height as usize,
                0,
                0,
                0,
            )
        };
        self.device.check(&format!(
            "oidnSetFilterImage({}) for the {}",
            name.to_string_lossy(),
            self.what
        ))
    }

    fn set_bool(&self, name: &CStr, value: bool) -> Result<()> {
        // SAFETY: live filter, NUL-terminated name.
        unsafe { (self.device.api.set_filter_bool)(self.raw, name.as_ptr(), value) };
        self.device.check(&format!(
            "oidnSetFilterBool({}) for the {}",
            name.to_string_lossy(),
            self.what
        ))
    }

    /// Commits the parameters and runs the filter to completion.
    fn run(&self) -> Result<()> {
        // SAFETY: live filter with its images set.
        unsafe { (self.device.api.commit_filter)(self.raw) };
        self.device
            .check(&format!("oidnCommitFilter for the {}", self.what))?;
        // SAFETY: as above; the synchronous call returns when done.
        unsafe { (self.device.api.execute_filter)(self.raw) };
        self.device
            .check(&format!("oidnExecuteFilter for the {}", self.what))
    }
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: live filter.
        unsafe { (self.device.api.release_filter)(self.raw) };
    }
}

/// Ok when the library loads and makes a device; else one line saying what
/// is missing and how to install it. Call it before rendering, so a missing
/// library is reported before the work and not after.
pub fn available() -> Result<(), String> {
    let api = api()?;
    let device = Device::new(api).map_err(|e| format!("{e:#}"))?;
    let version = device.version().map_err(|e| format!("{e:#}"))?;
    if version / 10000 != 2 {
        return Err(format!(
            "{}: Open Image Denoise {version} is not version 2.x; {}",
            api.path,
            install_hint()
        ));
    }
    Ok(())
}

/// Where the library was loaded from and its version ("2.5.1"), for
/// summaries; `None` when it is not available.
pub fn library_description() -> Option<String> {
    let api = api().ok()?;
    let device = Device::new(api).ok()?;
    let v = device.version().ok()?;
    Some(format!(
        "Open Image Denoise {}.{}.{} ({})",
        v / 10000,
        v / 100 % 100,
        v % 100,
        api.path
    ))
}

/// Denoises an HDR image (linear radiance, row-major, `width` x `height`)
/// with OIDN's "RT" filter and returns the denoised pixels.
///
/// `albedo` and `normal` are the optional auxiliary images (first-hit albedo
/// in [0, 1], world-space normals in [-1, 1]); a normal image needs an albedo
/// image. Given ones are noisy like the beauty (anti-aliased, depth of
/// field), so each is first denoised with its own RT filter and the beauty is
/// then filtered with `cleanAux` (OIDN's recommended flow for final frames).
pub fn denoise(
    width: u32,
    height: u32,
    color: &[[f32; 3]],
    albedo: Option<&[[f32; 3]]>,
    normal: Option<&[[f32; 3]]>,
) -> Result<Vec<[f32; 3]>> {
    let n = width as usize * height as usize;
    ensure!(
        width > 0 && height > 0,
        "cannot denoise an empty {width}x{height} image"
    );
    for (what, len) in [
        ("color", Some(color.len())),
        ("albedo", albedo.map(<[_]>::len)),
        ("normal", normal.map(<[_]>::len)),
    ] {
        if let Some(len) = len {
            ensure!(
                len == n,
                "cannot denoise: the {what} image has {len} pixels, expected {width}x{height} = {n}"
            );
        }
    }
    ensure!(
        normal.is_none() || albedo.is_some(),
        "cannot denoise with a normal image but no albedo image (Open Image Denoise needs both, or albedo alone)"
    );
    let api = api().map_err(|e| anyhow!(e))?;
    let device = Device::new(api)?;
    let color_buffer = device.buffer_from(color, "color")?;
    let albedo_buffer = albedo
        .map(|a| device.buffer_from(a, "albedo"))
        .transpose()?;
    let normal_buffer = normal
        .map(|a| device.buffer_from(a, "normal"))
        .transpose()?;
    let output = device.buffer(n, "output")?;

    // Prefilter the auxiliary images in place, each with its own filter.
    for (name, buffer, what) in [
        (c"albedo", &albedo_buffer, "albedo prefilter"),
        (c"normal", &normal_buffer, "normal prefilter"),
    ] {
        if let Some(buffer) = buffer {
            let filter = device.rt_filter(what)?;
            filter.set_image(name, buffer, width, height)?;
            filter.set_image(c"output", buffer, width, height)?;
            filter.run()?;
        }
    }

    let beauty = device.rt_filter("beauty")?;
    beauty.set_image(c"color", &color_buffer, width, height)?;
    if let Some(buffer) = &albedo_buffer {
        beauty.set_image(c"albedo", buffer, width, height)?;
    }
    if let Some(buffer) = &normal_buffer {
        beauty.set_image(c"normal", buffer, width, height)?;
    }
    beauty.set_image(c"output", &output, width, height)?;
    beauty.set_bool(c"hdr", true)?;
    beauty.set_bool(c"cleanAux", albedo_buffer.is_some())?;
    beauty.run()?;
    output.read()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn denoise_refuses_mismatched_sizes_before_loading() {
        let color = vec![[0.5f32; 3]; 6];
        let err = denoise(3, 3, &color, None, None).unwrap_err().to_string();
        assert!(err.contains("6 pixels") && err.contains("3x3"), "{err}");
        let albedo = vec![[0.5f32; 3]; 6];
        let err = denoise(3, 2, &color, None, Some(&albedo))
            .unwrap_err()
            .to_string();
        assert!(err.contains("no albedo"), "{err}");
        assert!(denoise(0, 2, &[], None, None).is_err());
    }

    #[test]
    fn installed_library_is_found_in_the_venv_layout() {
        let home = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("target/test-output/installed_library_is_found_in_the_venv_layout");
        let _ = std::fs::remove_dir_all(&home);
        assert_eq!(installed_library(&home), None);
        let dir = |python: &str| {
            home.join(INSTALL_DIR)
                .join("lib")
                .join(python)
                .join("site-packages/pyoidn/oidn/lib")
        };
        std::fs::create_dir_all(dir("python3.11")).unwrap();
        assert_eq!(installed_library(&home), None, "no library file yet");
        std::fs::write(dir("python3.11").join(LIBRARY_NAME), b"").unwrap();
        std::fs::create_dir_all(dir("python3.12")).unwrap();
        assert_eq!(
            installed_library(&home),
            Some(dir("python3.11").join(LIBRARY_NAME))
        );
    }

    #[test]
    fn install_hint_names_the_command_and_the_override() {
        let hint = install_hint();
        assert!(hint.contains("pip install --no-deps pyoidn"), "{hint}");
        assert!(hint.contains(LIBRARY_ENV) && hint.contains(LIBRARY_NAME));
        assert!(INSTALL_COMMAND.contains(INSTALL_DIR));
    }
}
