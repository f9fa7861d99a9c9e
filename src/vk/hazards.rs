//! Barriers derived from what compute dispatches read and write. Each dispatch names its resources
//! (its descriptor set's bindings: storage images and buffers it writes, everything it reads, the
//! list an indirect dispatch reads its size from); before it, one barrier orders exactly the earlier
//! accesses it conflicts with — a read or write of what an earlier dispatch wrote, or a write of
//! what one read — on the images and buffers concerned, and none where there is no conflict.
//! [`Hazards::flush`] makes everything still pending available at the end of a view, for whatever
//! the frame records next (another view, the compose pass, a copy). The rule is the one render
//! graphs use (kajiya's, wgpu-hal's usage transitions) within one queue: all images stay in
//! `GENERAL`, so no barrier changes a layout.

use std::cell::RefCell;

use ash::vk;

use super::descriptor::Binding;
use super::{barrier, Context};

/// A resource a dispatch touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    Image(vk::Image),
    Buffer(vk::Buffer),
}

/// How a dispatch touches a resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    pub resource: Resource,
    pub write: bool,
    /// Read as the size of an indirect dispatch (`DRAW_INDIRECT` stage).
    pub indirect: bool,
}

/// The accesses of a descriptor set's bindings: storage images and buffers may be written, the
/// others (read-only storage, uniform, sampled) are read.
pub fn accesses(bindings: &[Binding<'_>]) -> Vec<Access> {
    bindings
        .iter()
        .map(|b| {
            let (resource, write) = match b {
                Binding::Storage(buf) => (Resource::Buffer(buf.raw), true),
                Binding::StorageRead(buf) | Binding::Uniform(buf, ..) => (Resource::Buffer(buf.raw), false),
                Binding::StorageImage(im) => (Resource::Image(im.raw), true),
                Binding::StorageImageRead(im) | Binding::Sampled(im, _) => (Resource::Image(im.raw), false),
            };
            Access { resource, write, indirect: false }
        })
        .collect()
}

/// The accesses since the last barrier that covered them.
#[derive(Default)]
pub struct Hazards {
    state: RefCell<Pending>,
}

#[derive(Default)]
struct Pending {
    written: Vec<Resource>,
    read: Vec<Resource>,
}

const SHADER_READ_WRITE: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
        | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
        | vk::AccessFlags2::SHADER_SAMPLED_READ.as_raw()
        | vk::AccessFlags2::UNIFORM_READ.as_raw(),
);

impl Hazards {
    /// Records, before a dispatch with `accesses`, the barrier its conflicts with earlier dispatches
    /// need (none when there is none), and notes its own accesses. A barrier that has to be recorded
    /// makes every pending write available, not only the conflicting ones: its stages order all
    /// earlier compute work anyway, and one barrier over more resources is still one barrier, which
    /// later dispatches then need not repeat.
    pub fn before_dispatch(&self, ctx: &Context, cmd: vk::CommandBuffer, accesses: &[Access]) {
        let mut p = self.state.borrow_mut();
        let after_write = accesses.iter().any(|a| p.written.contains(&a.resource));
        let after_read: Vec<Resource> =
            accesses.iter().filter(|a| a.write && p.read.contains(&a.resource)).map(|a| a.resource).collect();
        if after_write || !after_read.is_empty() {
            let (mut dst_stage, mut dst_access) = (vk::PipelineStageFlags2::COMPUTE_SHADER, SHADER_READ_WRITE);
            if accesses.iter().any(|a| a.indirect) {
                dst_stage |= vk::PipelineStageFlags2::DRAW_INDIRECT;
                dst_access |= vk::AccessFlags2::INDIRECT_COMMAND_READ;
            }
            let src_write = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
            let src_read = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::NONE);
            let mut list: Vec<(Resource, barrier::Scope)> = p.written.iter().map(|&r| (r, src_write)).collect();
            list.extend(after_read.iter().filter(|r| !p.written.contains(r)).map(|&r| (r, src_read)));
            barrier::resources(ctx, cmd, &list, (dst_stage, dst_access));
            *p = Pending::default();
        }
        for a in accesses {
            let set = if a.write { &mut p.written } else { &mut p.read };
            if !set.contains(&a.resource) {
                set.push(a.resource);
            }
        }
    }

    /// Makes every pending write available to every later command and orders every pending read
    /// before later writes: one barrier, where anything is pending.
    pub fn flush(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let mut p = self.state.borrow_mut();
        if p.written.is_empty() && p.read.is_empty() {
            return;
        }
        let src = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        barrier::memory(ctx, cmd, src, barrier::ANY);
        *p = Pending::default();
    }

    /// Whether any access waits for a barrier (the tests' view of the state).
    #[cfg(test)]
    fn pending(&self) -> bool {
        let p = self.state.borrow();
        !p.written.is_empty() || !p.read.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::descriptor;
    use crate::vk::pipeline::Pipeline;
    use crate::vk::Image;

    /// `zero.comp` writes image `a`, then `accumulate.comp` reads `a` (`dependent`) or `b` and writes
    /// `c`, with the barriers `derive` says (none when false), on the validation layer with
    /// synchronization validation; returns the barriers recorded between them and what the layer
    /// reported.
    fn write_then_read(dependent: bool, derive: bool) -> (u64, crate::Result<()>) {
        let ctx = Context::new(true, None).expect("a Vulkan 1.3 device with validation (tools/setup)");
        let zero = Pipeline::compute(&ctx, crate::spirv!("zero.comp"), "zero", 16, &[]).unwrap();
        let add = Pipeline::compute(&ctx, crate::spirv!("accumulate.comp"), "add", 32, &[]).unwrap();
        let (usage, fmt) = (vk::ImageUsageFlags::STORAGE, vk::Format::R32G32B32A32_SFLOAT);
        let images: Vec<Image> =
            ["a", "b", "c"].iter().map(|n| Image::new(&ctx, (8, 8), fmt, 1, usage, n).unwrap()).collect();
        let pool = descriptor::pool(&ctx, 4, "test").unwrap();
        let hazards = Hazards::default();
        let counted = std::cell::Cell::new(0);
        ctx.commands
            .run(&ctx.device, |cmd| {
                for im in &images {
                    im.discard_to_general(&ctx, cmd, barrier::COMPUTE_READ_WRITE);
                }
                let before = ctx.counts.now();
                let read = if dependent { &images[0] } else { &images[1] };
                let steps: [(&Pipeline, [Binding; 2], Vec<u32>); 2] = [
                    (&zero, [Binding::StorageImage(&images[0]), Binding::StorageImage(&images[0])], vec![8, 8, 0, 0]),
                    (
                        &add,
                        [Binding::StorageImageRead(read), Binding::StorageImage(&images[2])],
                        vec![8, 8, 1, 0, 0, 0, 0, 0],
                    ),
                ];
                for (pipeline, binds, push) in &steps {
                    let set = descriptor::allocate(&ctx, pool, pipeline.set_layout)?;
                    pipeline.write_set(&ctx, set, binds)?;
                    if derive {
                        hazards.before_dispatch(&ctx, cmd, &accesses(binds));
                    }
                    pipeline.bind(&ctx, cmd, set, bytemuck::cast_slice(push));
                    // SAFETY: `cmd` is recording with a compute pipeline bound.
                    unsafe { ctx.raw().cmd_dispatch(cmd, 1, 1, 1) };
                }
                counted.set(ctx.counts.now().since(before).barriers);
                Ok(())
            })
            .unwrap();
        let reported = ctx.check_validation();
        // SAFETY: the submission was waited on; nothing uses these objects any more.
        unsafe { ctx.raw().destroy_descriptor_pool(pool, None) };
        zero.destroy(&ctx);
        add.destroy(&ctx);
        for im in images {
            im.destroy(&ctx);
        }
        (counted.get(), reported)
    }

    #[test]
    fn a_missing_barrier_is_a_synchronization_error() {
        let (barriers, reported) = write_then_read(true, false);
        assert_eq!(barriers, 0);
        let err = reported.expect_err("a read of an image written without a barrier").to_string();
        assert!(err.contains("SYNC-HAZARD-READ-AFTER-WRITE"), "{err}");
    }

    #[test]
    fn a_read_after_a_write_gets_one_barrier_and_an_unrelated_read_none() {
        let (barriers, reported) = write_then_read(true, true);
        assert_eq!(barriers, 1);
        reported.expect("the derived barrier orders the read after the write");
        let (barriers, reported) = write_then_read(false, true);
        assert_eq!(barriers, 0, "another image: nothing to order");
        reported.expect("no conflict");
    }

    #[test]
    fn reads_need_no_barrier_between_them_but_a_later_write_does() {
        let buf = |n: u64| Resource::Buffer(ash::vk::Handle::from_raw(n));
        let read = |n| Access { resource: buf(n), write: false, indirect: false };
        let write = |n| Access { resource: buf(n), write: true, indirect: false };
        let h = Hazards::default();
        let conflicts = |h: &Hazards, a: &[Access]| {
            let p = h.state.borrow();
            a.iter().any(|x| p.written.contains(&x.resource) || (x.write && p.read.contains(&x.resource)))
        };
        h.state.borrow_mut().read.push(buf(1));
        assert!(!conflicts(&h, &[read(1)]), "read after read");
        assert!(conflicts(&h, &[write(1)]), "write after read");
        h.state.borrow_mut().written.push(buf(2));
        assert!(conflicts(&h, &[read(2)]), "read after write");
        assert!(!conflicts(&h, &[write(3), read(4)]), "untouched resources");
        assert!(h.pending());
    }
}
