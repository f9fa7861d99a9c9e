//! *Export…*: the editor's material written in any format of [`Format::ALL`] (those `brdf-shop
//! export` writes), from a dialog of a format choice and a path field (egui has no native file
//! dialog), or from `--export FORMAT=PATH` in a scripted session; both end in [`export`], whose
//! result is the status line: what was written, or the error's one line. A failed export writes
//! nothing (`crate::export::write` is atomic) and the session goes on. No GPU and no window state here.

use std::path::{Path, PathBuf};

use crate::brdf::Material;
use crate::export::Format;

/// The name of a material file without its endings: `glossy.brdf.json` → `glossy`, `m.json` → `m`
/// (the name `brdf-shop export` gives the material's exports).
pub fn material_stem(path: &Path) -> String {
    crate::export::name_of(path)
}

/// The path the dialog offers for `format`: `<stem>.<extension>` beside `material` (the file the
/// material is saved to), or `material.<extension>` in the current folder when it has none.
pub fn default_path(material: Option<&Path>, format: Format) -> PathBuf {
    let Some(m) = material else { return PathBuf::from(format!("material.{}", format.extension())) };
    m.with_file_name(format!("{}.{}", material_stem(m), format.extension()))
}

/// Writes `m` in `format` to `path` and returns the status line: `exported F to P`, or `export
/// failed: ` and the reason (a folder that does not exist, a file that cannot be written, a material
/// the format cannot express). Every failure is the user's to fix, so none ends the session.
///
/// The export is named after `material_file` (the file the material is saved to) as `brdf-shop
/// export` names it, else after `path`; a note the format has on the material (a paper-model
/// material approximated twice in Blender) follows the success line.
pub fn export(m: &Material, format: Format, path: &Path, material_file: Option<&Path>) -> String {
    let name = material_file.map_or_else(|| material_stem(path), material_stem);
    let written = crate::fsio::check_output(format.name(), path)
        .and_then(|()| crate::export::write_named(m, format, &name, path));
    match written {
        Ok(()) => {
            let line = format!("exported {} to {}", format.name(), crate::fsio::show(path));
            match crate::export::note(m, format) {
                Some(note) => format!("{line} (note: {note})"),
                None => line,
            }
        }
        Err(e) => format!("export failed: {e}"),
    }
}

/// The *Export…* dialog: the format, the path field (relative paths from the working directory) and
/// whether it is shown. It keeps the last choice between openings.
pub struct Dialog {
    pub format: Format,
    pub path: String,
    pub open: bool,
}

impl Dialog {
    /// The dialog, closed, offering the first format beside the material's file.
    pub fn new(material: Option<&Path>) -> Dialog {
        let format = Format::ALL[0];
        Dialog { format, path: default_path(material, format).display().to_string(), open: false }
    }

    /// Picks `format`; a path ending in the old format's extension takes the new one's.
    pub fn choose(&mut self, format: Format) {
        let old = format!(".{}", self.format.extension());
        if let Some(base) = self.path.strip_suffix(&old) {
            self.path = format!("{base}.{}", format.extension());
        }
        self.format = format;
    }
}

/// Shows the dialog while it is open; a confirmed export is returned (format, path) and the dialog
/// closes (the status line tells how it went).
pub fn show(ctx: &egui::Context, d: &mut Dialog) -> Option<(Format, PathBuf)> {
    if !d.open {
        return None;
    }
    let mut confirmed = None;
    let mut close = false;
    egui::Window::new("Export…").collapsible(false).show(ctx, |ui| {
        let mut format = d.format;
        egui::ComboBox::from_label("format").selected_text(format.name()).show_ui(ui, |ui| {
            for f in Format::ALL {
                ui.selectable_value(&mut format, f, f.name());
            }
        });
        if format != d.format {
            d.choose(format);
        }
        let field = ui.text_edit_singleline(&mut d.path);
        let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        ui.horizontal(|ui| {
            if (ui.button("export").clicked() || enter) && !d.path.is_empty() {
                confirmed = Some((d.format, PathBuf::from(&d.path)));
                close = true;
            }
            if ui.button("cancel").clicked() {
                close = true;
            }
        });
    });
    if close {
        d.open = false;
    }
    confirmed
}
