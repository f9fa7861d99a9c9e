//! The BRDF model (docs/model.md, The paper model and The reciprocal model): the extended multi-lobe
//! Ward material of the paper (eq. 1–2), its sampling, its energy and reciprocity measurements, and
//! the material file (docs/formats.md, Material file).
//!
//! Plain Rust: nothing here may import `ash` or anything of the renderer; the renderer and the editor
//! depend on this module, never the reverse.

pub mod compensation;
pub mod energy;
pub mod file;
pub mod material;
pub mod sampling;
pub mod ward;

pub use material::{Lobe, Material, MaterialF32, ALPHA_MAX, ALPHA_MIN, GRAZING_COS};
pub use ward::Normalization;
