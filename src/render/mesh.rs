//! A mesh on the GPU: interleaved position + normal vertices (24 bytes) and 32-bit indices.

use ash::vk;

use crate::scene::mesh::Hidden;
use crate::scene::Mesh;
use crate::vk::{Buffer, Context};
use crate::Result;

pub const VERTEX_STRIDE: u32 = 24;

pub struct GpuMesh {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    /// The faces an eye outside the mesh never sees (the G-buffer pass skips them).
    pub hidden: Hidden,
    /// What this was built from (rebuilt only when the mesh changes).
    pub key: (String, usize, usize),
}

pub fn key(mesh: &Mesh) -> (String, usize, usize) {
    (mesh.name.clone(), mesh.positions.len(), mesh.indices.len())
}

impl GpuMesh {
    pub fn new(ctx: &Context, mesh: &Mesh) -> Result<GpuMesh> {
        let vertex_data: Vec<f32> =
            mesh.positions.iter().zip(&mesh.normals).flat_map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z]).collect();
        let vertices = Buffer::upload(
            ctx,
            bytemuck::cast_slice(&vertex_data),
            vk::BufferUsageFlags::VERTEX_BUFFER,
            "mesh.vertices",
        )?;
        let indices = match Buffer::upload(
            ctx,
            bytemuck::cast_slice(&mesh.indices),
            vk::BufferUsageFlags::INDEX_BUFFER,
            "mesh.indices",
        ) {
            Ok(b) => b,
            Err(e) => {
                vertices.destroy(ctx);
                return Err(e);
            }
        };
        Ok(GpuMesh {
            vertices,
            indices,
            index_count: mesh.indices.len() as u32,
            hidden: mesh.hidden_faces(),
            key: key(mesh),
        })
    }

    pub fn destroy(self, ctx: &Context) {
        self.vertices.destroy(ctx);
        self.indices.destroy(ctx);
    }
}
