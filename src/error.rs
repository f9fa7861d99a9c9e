//! The library's one error type. The binary turns it into one line on stderr and an exit status
//! (1 for [`Error::is_user_error`], 2 otherwise).

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input: `origin` names the file (or `stdin`), `message` the field or line and what is wrong.
    #[error("{origin}: {message}")]
    Input { origin: String, message: String },
    /// A brush stroke that cannot be applied where it was made.
    #[error("{0}")]
    Brush(String),
    /// A Vulkan call failed.
    #[error("{call} failed: {result}{}", if *.result == ash::vk::Result::ERROR_DEVICE_LOST { " (device lost)" } else if matches!(*.result, ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | ash::vk::Result::ERROR_OUT_OF_HOST_MEMORY) { " (out of memory)" } else { "" })]
    Vulkan { call: &'static str, result: ash::vk::Result },
    /// The validation layer reported an error: a bug in this program.
    #[error("Vulkan validation: {0}")]
    Validation(String),
    /// No usable Vulkan device (exit status 2); the message says how to get one.
    #[error("{0}")]
    NoDevice(String),
    #[error("{}: {source}", crate::fsio::show(path))]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    pub fn input(origin: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Input { origin: origin.into(), message: message.into() }
    }

    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }

    /// Whether the user can fix this by changing their input (exit status 1). A file that cannot be
    /// read or written (missing, a folder, no permission, disk full) is the user's to fix.
    pub fn is_user_error(&self) -> bool {
        matches!(self, Error::Input { .. } | Error::Brush(_) | Error::Io { .. })
    }

    pub fn is_device_lost(&self) -> bool {
        matches!(self, Error::Vulkan { result: ash::vk::Result::ERROR_DEVICE_LOST, .. })
    }
}

pub type Result<T> = std::result::Result<T, Error>;
