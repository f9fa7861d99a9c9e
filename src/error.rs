//! The library's one error type. The binary turns it into one line on stderr and the exit status
//! of its kind ([`Error::exit_status`]):
//!
//! | status | kind | variants |
//! | --- | --- | --- |
//! | [`EXIT_USER`] (1) | the user's input: fixed by changing a file, flag or field | `Input`, `Brush`, `Io` |
//! | [`EXIT_SYSTEM`] (2) | the device, its driver or the operating system cannot do what was asked | `Vulkan`, `NoDevice`, `System` |
//! | [`EXIT_VALIDATION`] (4) | the Vulkan validation layer reported an error | `Validation` |
//! | [`EXIT_BUG`] (5) | an invariant of this program does not hold | `Bug` |
//!
//! The binary keeps 3 for `check`'s "not physically correct" and 130 for Ctrl-C
//! ([`crate::interrupt::EXIT_STATUS`]). Messages show paths through [`crate::text`], which imports
//! nothing of this crate.

use std::path::PathBuf;

/// Exit status of an error the user fixes by changing their input.
pub const EXIT_USER: u8 = 1;
/// Exit status of a failure of the device, its driver or the operating system.
pub const EXIT_SYSTEM: u8 = 2;
/// Exit status of an error the Vulkan validation layer reported.
pub const EXIT_VALIDATION: u8 = 4;
/// Exit status of a broken internal invariant: a bug in this program.
pub const EXIT_BUG: u8 = 5;

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
    /// The validation layer reported an error (a bug in this program or the driver): its messages,
    /// and nothing else. A check of this program's own is [`Error::Bug`].
    #[error("Vulkan validation: {0}")]
    Validation(String),
    /// No usable Vulkan device, display or window surface; the message says how to get one.
    #[error("{0}")]
    NoDevice(String),
    /// The operating system refused a resource the program needs to go on (a thread). Of the same
    /// kind as a device failure, and the same exit status: neither the user's input nor a bug can
    /// change it, a machine with more to spare can.
    #[error("{what}: {source}")]
    System {
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// An invariant of this program does not hold: a bug in brdf-shop, never the user's input, the
    /// device or the validation layer.
    #[error("internal error (a bug in brdf-shop): {0}")]
    Bug(String),
    #[error("{}: {source}", crate::text::show(path))]
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

    /// The binary's exit status for this error (the module's table). A file that cannot be read or
    /// written (missing, a folder, no permission, disk full) is the user's to fix.
    pub fn exit_status(&self) -> u8 {
        match self {
            Error::Input { .. } | Error::Brush(_) | Error::Io { .. } => EXIT_USER,
            Error::Vulkan { .. } | Error::NoDevice(_) | Error::System { .. } => EXIT_SYSTEM,
            Error::Validation(_) => EXIT_VALIDATION,
            Error::Bug(_) => EXIT_BUG,
        }
    }

    /// Whether the user can fix this by changing their input ([`EXIT_USER`]).
    pub fn is_user_error(&self) -> bool {
        self.exit_status() == EXIT_USER
    }

    pub fn is_device_lost(&self) -> bool {
        matches!(self, Error::Vulkan { result: ash::vk::Result::ERROR_DEVICE_LOST, .. })
    }
}

pub type Result<T> = std::result::Result<T, Error>;

#[cfg(test)]
mod tests {
    use super::*;

    fn io_error() -> std::io::Error {
        std::io::Error::from(std::io::ErrorKind::WouldBlock)
    }

    /// One of every variant, with the status and the start of the line it must give.
    fn every_variant() -> Vec<(Error, u8, &'static str)> {
        vec![
            (Error::input("m.brdf.json", "lobes[0].albedo: not a number"), EXIT_USER, "m.brdf.json: "),
            (Error::Brush("the stroke is off the canvas".into()), EXIT_USER, "the stroke"),
            (Error::io("missing/o.png", std::io::ErrorKind::NotFound.into()), EXIT_USER, "missing/o.png: "),
            (
                Error::Vulkan { call: "vkQueueSubmit", result: ash::vk::Result::ERROR_DEVICE_LOST },
                EXIT_SYSTEM,
                "vkQueueSubmit failed: ",
            ),
            (Error::NoDevice("no Vulkan 1.3 driver".into()), EXIT_SYSTEM, "no Vulkan 1.3 driver"),
            (
                Error::System { what: "cannot start a thread", source: io_error() },
                EXIT_SYSTEM,
                "cannot start a thread: ",
            ),
            (Error::Validation("1 validation error(s)".into()), EXIT_VALIDATION, "Vulkan validation: "),
            (Error::Bug("a frame was begun twice".into()), EXIT_BUG, "internal error (a bug in brdf-shop): "),
        ]
    }

    #[test]
    fn each_kind_has_its_status_and_label() {
        for (e, status, start) in every_variant() {
            assert_eq!(e.exit_status(), status, "{e:?}");
            assert_eq!(e.is_user_error(), status == EXIT_USER, "{e:?}");
            let line = e.to_string();
            assert!(line.starts_with(start), "{e:?}: {line}");
            // Only the validation layer's messages carry its label.
            assert_eq!(line.starts_with("Vulkan validation"), matches!(e, Error::Validation(_)), "{line}");
        }
    }

    #[test]
    fn every_variant_is_covered() {
        // A new variant fails to compile here; add it to `every_variant` and to the count.
        let arm = |e: &Error| match e {
            Error::Input { .. } => 0,
            Error::Brush(_) => 1,
            Error::Vulkan { .. } => 2,
            Error::Validation(_) => 3,
            Error::NoDevice(_) => 4,
            Error::System { .. } => 5,
            Error::Bug(_) => 6,
            Error::Io { .. } => 7,
        };
        let seen: std::collections::BTreeSet<i32> = every_variant().iter().map(|(e, _, _)| arm(e)).collect();
        assert_eq!(seen.len(), 8, "{seen:?}");
    }

    /// [`Error::Validation`] carries the validation layer's messages and nothing else: the one
    /// place in the library that makes it is `vk::Context::check_validation` (src/vk/mod.rs); a
    /// check of the program's own is [`Error::Bug`]. The binary makes one on request
    /// (`BRDF_SHOP_FAIL`, debug builds) and in its tests (src/main.rs).
    #[test]
    fn only_the_layers_messages_are_validation_errors() {
        fn walk(dir: &std::path::Path, found: &mut Vec<(std::path::PathBuf, usize)>) {
            for entry in std::fs::read_dir(dir).expect("src/ is readable") {
                let path = entry.expect("a folder entry").path();
                if path.is_dir() {
                    walk(&path, found);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).expect("a source file");
                    for (k, line) in text.lines().enumerate() {
                        if line.contains("Error::Validation(") {
                            found.push((path.clone(), k + 1));
                        }
                    }
                }
            }
        }
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut found = Vec::new();
        walk(&src, &mut found);
        let allowed = ["error.rs", "main.rs", "vk/mod.rs"].map(|f| src.join(f));
        let others: Vec<String> = found
            .iter()
            .filter(|(p, _)| !allowed.contains(p))
            .map(|(p, line)| format!("{}:{line}", p.display()))
            .collect();
        assert!(others.is_empty(), "Error::Validation for what the layer did not report: {others:#?}");
        assert_eq!(found.iter().filter(|(p, _)| *p == allowed[2]).count(), 1, "{found:?}");
    }

    #[test]
    fn statuses_are_distinct() {
        // The binary checks them against its own (`check`'s 3) in `main.rs`.
        let all = [EXIT_USER, EXIT_SYSTEM, EXIT_VALIDATION, EXIT_BUG, crate::interrupt::EXIT_STATUS];
        for (i, a) in all.iter().enumerate() {
            assert!(*a != 0 && !all[i + 1..].contains(a), "{all:?}");
        }
    }
}
