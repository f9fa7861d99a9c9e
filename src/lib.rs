//! brdf-shop: paint highlights on a spherical canvas and get a physically plausible multi-lobe Ward
//! BRDF (Colbert, Pattanaik, Křivánek 2006, "BRDF-Shop").
//!
//! `brdf` is the model, `brush` the canvas and the brushes; both are plain Rust with no GPU code.
//! `vk` owns everything Vulkan. `layout` is where the editor's panel and views sit in its window,
//! plain geometry shared by the editor and `measure` (which sits below the editor and imports nothing
//! from it).

// `!(x > 0.0)` is how this code says "not a positive number, NaN included"; the lint would
// have it written `x <= 0.0`, which lets NaN through. Per-channel `for c in 0..3` loops read
// better than zipped iterators over three arrays.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod brdf;
pub mod brush;
pub mod editor;
pub mod error;
pub mod export;
pub mod fsio;
pub mod imageio;
pub mod interrupt;
pub mod layout;
pub mod measure;
pub mod plot;
pub mod reference;
pub mod render;
pub mod rng;
pub mod scene;
pub mod text;
pub mod vk;

pub use error::{Error, Result};
