//! Which Embree dpm runs on: the library's version as the device reports it, the headers' the
//! backend was compiled against, and the backend's name.

use super::{Device, EmbreeError, backend, shim};
use std::ffi::c_long;
use std::fmt;
use std::sync::OnceLock;

/// An Embree version, as `rtcGetDeviceProperty` reports it (`major * 10000 + minor * 100 +
/// patch`). Displays as `Embree 4.4.0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Version {
    pub major: u32,
    pub minor: u32,
    pub patch: u32,
}

impl Version {
    fn from_raw(raw: c_long) -> Self {
        let raw = u32::try_from(raw).unwrap_or(0);
        Self {
            major: raw / 10_000,
            minor: raw / 100 % 100,
            patch: raw % 100,
        }
    }
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Embree {}.{}.{}", self.major, self.minor, self.patch)
    }
}

impl Device {
    /// The version of the Embree library this device runs on (`RTC_DEVICE_PROPERTY_VERSION`).
    pub fn version(&self) -> Version {
        // SAFETY: live device.
        let raw = unsafe { shim::dpm_rtc_library_version(self.inner.raw) };
        Version::from_raw(raw)
    }
}

/// The Embree library in use, e.g. `Embree 4.4.0` (asked of a device made once per process), or
/// why no device could be made.
pub fn version() -> Result<Version, EmbreeError> {
    static VERSION: OnceLock<Result<Version, EmbreeError>> = OnceLock::new();
    VERSION
        .get_or_init(|| Device::new().map(|d| d.version()))
        .clone()
}

/// [`version`] as text for reports: `Embree 4.4.0`, or `Embree unavailable (...)`.
pub fn version_string() -> String {
    match version() {
        Ok(v) => v.to_string(),
        Err(e) => format!("Embree unavailable ({e})"),
    }
}

/// Which backend this build was made with: `"Embree 3"` or `"Embree 4"`.
pub const BACKEND: &str = backend::NAME;

/// The version of the headers the backend was compiled against (Embree 4: the 4.2.0 headers of
/// `embree4-sys`, while the library is 4.4.0).
pub fn header_version() -> Version {
    // SAFETY: returns a constant.
    Version::from_raw(c_long::from(unsafe { shim::dpm_rtc_header_version() }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_name_the_backend() {
        let major = if cfg!(feature = "embree4") { 4 } else { 3 };
        assert_eq!(BACKEND, format!("Embree {major}"));
        assert_eq!(header_version().major, major);
        let v = version().unwrap();
        assert_eq!(v.major, major);
        assert!(v >= header_version(), "library {v} older than its headers");
        assert_eq!(
            Version::from_raw(40400).to_string(),
            "Embree 4.4.0".to_string()
        );
        assert_eq!(Version::from_raw(31305).to_string(), "Embree 3.13.5");
    }
}
