//! What a render looks at, as plain CPU data: the environment map (loading, statistics, mip chain,
//! SH9 projection, brightest direction, importance-sampling distribution), the meshes and the camera.
//! Shared by the GPU renderer (`render`) and the CPU reference (`reference`); imports nothing from
//! `ash`.

pub mod camera;
pub mod env;
pub mod keylight;
pub mod mesh;

pub use camera::Camera;
pub use env::Environment;
pub use mesh::Mesh;
