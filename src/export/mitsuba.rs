//! `--format mitsuba`: a Python file that registers the material as the Mitsuba 3 BSDF plug-in
//! `brdfshop` and, run as a program, renders it (`mitsuba_plugin.py`, its template, documents both).
//! The material travels as its own file text (`Material::to_json`), which the plug-in reads the way
//! `src/brdf/file.rs` does.

use crate::brdf::Material;

const TEMPLATE: &str = include_str!("mitsuba_plugin.py");
const SLOT: &str = "@MATERIAL_JSON@";

pub fn mitsuba(m: &Material) -> String {
    // The material file's JSON has no `"""` and no backslash (numbers and fixed names only), so it
    // sits in a raw triple-quoted Python string as it is.
    let json = m.to_json();
    debug_assert!(!json.contains("\"\"\"") && !json.contains('\\'));
    TEMPLATE.replacen(SLOT, json.trim_end(), 1)
}
