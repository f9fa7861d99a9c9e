//! `--format mitsuba`: a Python file that registers the material as the Mitsuba 3 BSDF plug-in
//! `brdfshop` and, run as a program, renders it (`mitsuba_plugin.py`, its template, documents both).
//! The material travels as its own file text (`Material::to_json`), which the plug-in reads the way
//! `src/brdf/file.rs` does; an energy-preserving material's compensation tables, baked here, as
//! the words of `compensation::words`.

use crate::brdf::compensation::{self, Table};
use crate::brdf::Material;

const TEMPLATE: &str = include_str!("mitsuba_plugin.py");
const SLOT: &str = "@MATERIAL_JSON@";
const TABLE_SLOT: &str = "None  # @TABLE_WORDS@";

pub fn mitsuba(m: &Material) -> String {
    // The material file's JSON has no `"""` and no backslash (numbers and fixed names only), so it
    // sits in a raw triple-quoted Python string as it is.
    let json = m.to_json();
    debug_assert!(!json.contains("\"\"\"") && !json.contains('\\'));
    let tables = match m.tables() {
        Some(tables) => {
            let refs: Vec<Option<&Table>> = tables.iter().map(|t| Some(&**t)).collect();
            let words: Vec<String> = compensation::words(&refs).iter().map(|w| format!("0x{w:08x}")).collect();
            let lines: Vec<String> = words.chunks(8).map(|c| format!("    {},", c.join(", "))).collect();
            format!("[\n{}\n]", lines.join("\n"))
        }
        None => "None".into(),
    };
    TEMPLATE.replacen(SLOT, json.trim_end(), 1).replacen(TABLE_SLOT, &tables, 1)
}
