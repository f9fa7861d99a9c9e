//! Descriptor set layouts (made from the shaders' bindings, `reflect::layout`), one pool per
//! renderer, and the writes that point sets at buffers and images: a pass lists one resource per
//! binding, in the order of the binding numbers. [`check`] holds such a list to the layout of the
//! pipeline whose set it is written to, before it is written.

use ash::vk;

use super::{vk_err, Buffer, Context, Image};
use crate::error::{Error, Result};

/// The set layout of `declared` (binding `i` of type `declared[i]`, one descriptor, none where
/// it is `None`), visible to `stages`, unnamed (a pipeline names it, [`super::pipeline::Pipeline::name`]).
pub fn layout_on(
    raw: &ash::Device,
    declared: &[Option<Declared>],
    stages: vk::ShaderStageFlags,
) -> Result<vk::DescriptorSetLayout> {
    let bindings: Vec<_> = declared
        .iter()
        .enumerate()
        .filter_map(|(i, d)| {
            d.map(|d| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(d.ty)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: the device is live; the layout is destroyed by its owner.
    unsafe { raw.create_descriptor_set_layout(&info, None) }.map_err(vk_err("vkCreateDescriptorSetLayout"))
}

/// A pool big enough for `sets` sets of up to 16 descriptors of each type the renderer uses.
pub fn pool(ctx: &Context, sets: u32, name: &str) -> Result<vk::DescriptorPool> {
    let sizes = [
        vk::DescriptorType::STORAGE_BUFFER,
        vk::DescriptorType::STORAGE_IMAGE,
        vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        vk::DescriptorType::UNIFORM_BUFFER,
    ]
    .map(|ty| vk::DescriptorPoolSize { ty, descriptor_count: sets * 16 });
    let info = vk::DescriptorPoolCreateInfo::default().max_sets(sets).pool_sizes(&sizes);
    // SAFETY: the device is live; the pool is destroyed by its owner.
    let p = unsafe { ctx.raw().create_descriptor_pool(&info, None) }.map_err(vk_err("vkCreateDescriptorPool"))?;
    ctx.device.set_name(p, name);
    Ok(p)
}

pub fn allocate(ctx: &Context, pool: vk::DescriptorPool, layout: vk::DescriptorSetLayout) -> Result<vk::DescriptorSet> {
    let layouts = [layout];
    let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
    // SAFETY: pool and layout are live objects of this device.
    let sets = unsafe { ctx.raw().allocate_descriptor_sets(&info) }.map_err(vk_err("vkAllocateDescriptorSets"))?;
    Ok(sets[0])
}

/// What one binding points at, and whether the shader may write it (what `vk::hazards` orders
/// later dispatches after).
pub enum Binding<'a> {
    /// A storage buffer the shader may write.
    Storage(&'a Buffer),
    /// A storage buffer the shader only reads (`readonly` in GLSL).
    StorageRead(&'a Buffer),
    /// `range` bytes of a uniform buffer from `offset` (a multiple of the device's
    /// `minUniformBufferOffsetAlignment`; `range` at most its `maxUniformBufferRange`).
    Uniform(&'a Buffer, u64, u64),
    /// A storage image (`GENERAL`) the shader may write.
    StorageImage(&'a Image),
    /// A storage image (`GENERAL`) the shader only reads.
    StorageImageRead(&'a Image),
    /// An image sampled through `sampler` (`SHADER_READ_ONLY_OPTIMAL`).
    Sampled(&'a Image, vk::Sampler),
}

/// Points the bindings of `set` (whose layout is `declared`) at the given resources: binding `i`
/// at `bindings[i]`, except where the layout has no binding `i` (a resource compiled out of the
/// shader), which is left out.
pub fn write(ctx: &Context, set: vk::DescriptorSet, declared: &[Option<Declared>], bindings: &[Binding<'_>]) {
    let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
        .iter()
        .map(|b| match b {
            Binding::Storage(buf) | Binding::StorageRead(buf) => [buf.descriptor()],
            Binding::Uniform(buf, offset, range) => [buf.descriptor().offset(*offset).range(*range)],
            _ => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let images: Vec<[vk::DescriptorImageInfo; 1]> = bindings
        .iter()
        .map(|b| match *b {
            Binding::StorageImage(im) | Binding::StorageImageRead(im) => {
                [vk::DescriptorImageInfo::default().image_view(im.view).image_layout(vk::ImageLayout::GENERAL)]
            }
            Binding::Sampled(im, sampler) => [vk::DescriptorImageInfo::default()
                .image_view(im.view)
                .sampler(sampler)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
            _ => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet> = bindings
        .iter()
        .enumerate()
        .filter(|(i, _)| declared.get(*i).is_some_and(Option::is_some))
        .map(|(i, b)| {
            let w = vk::WriteDescriptorSet::default().dst_set(set).dst_binding(i as u32);
            let w = w.descriptor_type(b.ty());
            match b {
                Binding::Storage(_) | Binding::StorageRead(_) | Binding::Uniform(..) => w.buffer_info(&buffers[i]),
                Binding::StorageImage(_) | Binding::StorageImageRead(_) | Binding::Sampled(..) => {
                    w.image_info(&images[i])
                }
            }
        })
        .collect();
    // SAFETY: the set and every resource are live; the info arrays outlive the call.
    unsafe { ctx.raw().update_descriptor_sets(&writes, &[]) };
}

impl Binding<'_> {
    pub fn ty(&self) -> vk::DescriptorType {
        match self {
            Binding::Storage(_) | Binding::StorageRead(_) => vk::DescriptorType::STORAGE_BUFFER,
            Binding::Uniform(..) => vk::DescriptorType::UNIFORM_BUFFER,
            Binding::StorageImage(_) | Binding::StorageImageRead(_) => vk::DescriptorType::STORAGE_IMAGE,
            Binding::Sampled(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        }
    }

    /// Whether the binding passes a storage resource as read only ([`Binding::StorageRead`],
    /// [`Binding::StorageImageRead`]): the dispatch is taken to leave it unchanged.
    pub fn read_only(&self) -> bool {
        matches!(self, Binding::StorageRead(_) | Binding::StorageImageRead(_))
    }
}

/// One binding of a pipeline's set: its type, and whether its shaders may write it (a storage
/// resource not `readonly` in some stage), as `reflect::layout` reads them from the shaders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Declared {
    pub ty: vk::DescriptorType,
    pub writable: bool,
}

/// Checks `bindings`, about to be written to a set of pipeline `pipeline` whose layout is
/// `declared`: a resource for each binding of the layout, each of its type, and none passed
/// read-only where the shader may write it (`vk::hazards` orders later dispatches after declared
/// writes alone, so such a write would go without its barrier). Resources at numbers the layout
/// lacks are allowed (compiled out of the shader; [`write`] leaves them out). A mismatch is a bug in
/// the program ([`Error::Bug`]); the error names the pipeline, each binding concerned, what the
/// shader has and what was written.
pub fn check(pipeline: &str, declared: &[Option<Declared>], bindings: &[Binding<'_>]) -> Result<()> {
    check_written(pipeline, declared, bindings.iter().map(|b| (b.ty(), b.read_only())))
}

/// [`check`] on what each binding is written as: its type, and whether it is passed read-only.
fn check_written(
    pipeline: &str,
    declared: &[Option<Declared>],
    written: impl ExactSizeIterator<Item = (vk::DescriptorType, bool)>,
) -> Result<()> {
    let mut problems = Vec::new();
    if written.len() < declared.len() {
        problems.push(format!("{} bindings written, the shader has {}", written.len(), declared.len()));
    }
    for (i, ((ty, read_only), d)) in written.zip(declared).enumerate() {
        let Some(d) = d else { continue };
        if ty != d.ty {
            problems.push(format!("binding {i}: the shader has {:?}, written {ty:?}", d.ty));
        } else if read_only && d.writable {
            problems.push(format!("binding {i}: {ty:?} written read-only, but the shader may write it"));
        }
    }
    if problems.is_empty() {
        return Ok(());
    }
    Err(Error::Bug(format!(
        "pipeline `{pipeline}`: the resources written to its set do not match its shader: {}",
        problems.join("; ")
    )))
}

#[cfg(test)]
mod tests;
