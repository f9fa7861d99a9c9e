//! The bench's trust checks: the control rows' stability rule (the same configuration measured at the
//! start, middle and end of a run, and as its goal row, must agree) and the device clocks read beside
//! a run. Pure arithmetic and a read-only query; nothing here changes a device setting.

/// How far apart the control rows' medians may be before a run is unstable: 5 % of the smallest.
/// Unlocked GPU clocks move more than that when a device drops a clock step between rows, and
/// steady runs on a quiet machine stay well inside it.
pub const CONTROL_TOLERANCE: f64 = 0.05;

/// What the control rows say about a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    /// `(max − min) / min` of the medians (0 with fewer than two).
    pub spread: f64,
    pub stable: bool,
}

/// The stability rule: a run is stable when its control rows' medians differ by at most
/// [`CONTROL_TOLERANCE`] of the smallest. A run with fewer than two control rows is stable (nothing
/// to compare); a non-finite or non-positive median makes it unstable (a frame that timed nothing).
pub fn stability(medians: &[f64]) -> Stability {
    if medians.len() < 2 {
        return Stability { spread: 0.0, stable: true };
    }
    if medians.iter().any(|m| !m.is_finite() || *m <= 0.0) {
        return Stability { spread: f64::INFINITY, stable: false };
    }
    let min = medians.iter().copied().fold(f64::INFINITY, f64::min);
    let max = medians.iter().copied().fold(0.0, f64::max);
    let spread = (max - min) / min;
    Stability { spread, stable: spread <= CONTROL_TOLERANCE }
}

/// The SM and memory clocks and the active throttle reasons of the first NVIDIA device, read with
/// `nvidia-smi --query-gpu=… --format=csv,noheader` (read-only). `None` where the device is not
/// NVIDIA's, the command is missing or its answer does not parse.
pub fn clocks(vendor_id: u32) -> Option<serde_json::Value> {
    if vendor_id != NVIDIA {
        return None;
    }
    let out = std::process::Command::new("nvidia-smi")
        .args(["--query-gpu=clocks.sm,clocks.mem,clocks_throttle_reasons.active", "--format=csv,noheader"])
        .stdin(std::process::Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    parse_clocks(String::from_utf8_lossy(&out.stdout).lines().next()?)
}

/// PCI vendor id of NVIDIA.
pub const NVIDIA: u32 = 0x10de;

/// `"1980 MHz, 2619 MHz, 0x0000000000000000"` → `{"sm_mhz": 1980, "mem_mhz": 2619,
/// "throttle_reasons_active": "0x0000000000000000"}`.
pub fn parse_clocks(line: &str) -> Option<serde_json::Value> {
    let parts: Vec<&str> = line.split(',').map(str::trim).collect();
    let [sm, mem, reasons] = parts[..] else { return None };
    let mhz = |s: &str| s.strip_suffix("MHz").map(str::trim).and_then(|v| v.parse::<u32>().ok());
    Some(serde_json::json!({ "sm_mhz": mhz(sm)?, "mem_mhz": mhz(mem)?, "throttle_reasons_active": reasons }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clocks_parse_from_nvidia_smi() {
        let v = parse_clocks("1980 MHz, 2619 MHz, 0x0000000000000004").unwrap();
        assert_eq!(v["sm_mhz"], 1980);
        assert_eq!(v["mem_mhz"], 2619);
        assert_eq!(v["throttle_reasons_active"], "0x0000000000000004");
        assert!(parse_clocks("[N/A], 2619 MHz, 0x0").is_none());
        assert!(parse_clocks("1980 MHz").is_none());
        assert_eq!(clocks(0x10005), None, "not an NVIDIA device: no query");
    }
}
