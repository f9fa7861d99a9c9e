//! The descriptor bindings a SPIR-V module declares, and the set layout a pipeline makes of them.
//! A pass's GLSL is the one place its bindings are declared (`layout(binding = i)`, the type, and
//! `readonly` for what it only reads): [`layout`] reads them from the compiled shaders when the
//! pipeline is made, so the descriptor set layout cannot fall out of step with the shader. The
//! pass names each binding's resource once, when it writes a set (`descriptor::Binding`, read-only
//! or writable), and [`super::descriptor::check`] holds that list to the layout: the type of each
//! binding, and no resource passed read-only where the shader may write it (the derived barriers,
//! `vk::hazards`, follow what the list says).
//!
//! This module reads the few instructions it needs itself (names, `OpSource`, `OpDecorate`,
//! `OpMemberDecorate`, the image, sampler, array, struct and pointer types, constants and
//! `OpVariable`), with the opcode and enum values of the `spirv` crate (the SPIR-V grammar as Rust
//! enums). The reflection crates do not read this program's shaders: `rspirv`'s module loader
//! rejects the `OpExecutionModeId` that shaderc emits for every Vulkan 1.3 compute shader, and the
//! `OpSource` text that glslang writes for a shader with non-ASCII comments (not valid UTF-8:
//! `gbuffer.frag`); `spirq` fails to evaluate the `OpSpecConstantOp LogicalNot` of
//! `compact.comp`.
//!
//! Which bindings a module holds: `build.rs` compiles with shaderc's performance optimisation,
//! which removes every resource that no code reads, and keeps the resources that only a
//! specialisation constant's branch reads (the constant is unknown when compiling). So a module's
//! bindings are those some specialisation of it may use; a binding the GLSL declares and never
//! reads is absent. A pass's list may name resources at bindings its layout lacks (a resource
//! compiled out, or, for `EvalPass::from_spirv`, an exported shader that reads no material
//! buffer): they are not written.
//!
//! Owns no Vulkan object and calls no Vulkan function.

use std::collections::{HashMap, HashSet};

use ash::vk;
use spirv::{Decoration, Dim, Op, StorageClass};

use super::descriptor::Declared;
use crate::error::{Error, Result};

/// One descriptor binding of a shader module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderBinding {
    pub set: u32,
    pub binding: u32,
    pub ty: vk::DescriptorType,
    /// Descriptors in the binding: 1, an array's length, or 0 for an array of unknown size.
    pub count: u32,
    /// The variable's name in the source (`OpName`), empty where the module carries no names.
    pub name: String,
    /// Whether the shader may write through the binding: a storage buffer, image or texel buffer
    /// not `readonly` in GLSL (SPIR-V `NonWritable` on the variable or, for a buffer block, on
    /// every member of its block, where glslang puts it). False for the types no shader writes.
    pub writable: bool,
}

/// What reflection reads from one module.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Reflection {
    /// The file the module was compiled from, without its folder (`OpSource` with debug
    /// information, which `build.rs` asks for); `None` without it.
    pub source: Option<String>,
    /// The descriptor bindings, by set and binding.
    pub bindings: Vec<ShaderBinding>,
}

/// Why a module could not be read: not SPIR-V, cut short, or a descriptor of a type this module
/// does not know.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Malformed(String);

/// The descriptor bindings of the SPIR-V module `spv` (either byte order).
pub fn reflect(spv: &[u8]) -> std::result::Result<Reflection, Malformed> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spv)).map_err(|e| Malformed(e.to_string()))?;
    let tables = Tables::read(&words)?;
    let mut bindings = Vec::new();
    for var in &tables.variables {
        if let Some(b) = tables.descriptor(var)? {
            bindings.push(b);
        }
    }
    bindings.sort_by_key(|b| (b.set, b.binding));
    let source = tables.source_file.and_then(|id| tables.strings.get(&id)).map(|path| file_name(path));
    Ok(Reflection { source, bindings })
}

/// The set layout of pipeline `pipeline`, made from the bindings of its shader `modules`: entry
/// `i` is binding `i` of set 0, with its type and whether some module may write it
/// ([`ShaderBinding::writable`]), or `None` where no module holds binding `i` (a resource compiled
/// out, see the module note). Each binding must be in set 0 and a single descriptor, and modules
/// that share a binding must give it one type; otherwise, or for a module this cannot read, the
/// error is a bug in the program ([`Error::Bug`]) that names the pipeline, the shader file and the
/// binding.
pub fn layout(pipeline: &str, modules: &[&[u8]]) -> Result<Vec<Option<Declared>>> {
    let mut problems = Vec::new();
    let mut layout: Vec<Option<Declared>> = Vec::new();
    for spv in modules {
        let found = reflect(spv)
            .map_err(|e| Error::Bug(format!("pipeline `{pipeline}`: its SPIR-V cannot be reflected: {e}")))?;
        let shader = found.source.as_deref().unwrap_or(pipeline);
        for b in &found.bindings {
            let name = if b.name.is_empty() { String::new() } else { format!(" (`{}`)", b.name) };
            let at = format!("shader {shader}, binding {}{name}", b.binding);
            if b.set != 0 {
                problems.push(format!("{at}: in set {}, a pipeline has set 0 alone", b.set));
                continue;
            }
            if b.count != 1 {
                problems.push(format!("{at}: an array of {} descriptors, a binding holds one", b.count));
                continue;
            }
            let i = b.binding as usize;
            if layout.len() <= i {
                layout.resize(i + 1, None);
            }
            match &mut layout[i] {
                Some(d) if d.ty != b.ty => {
                    problems.push(format!("{at}: {:?} here, {:?} in another stage", b.ty, d.ty));
                }
                Some(d) => d.writable |= b.writable,
                slot => *slot = Some(Declared { ty: b.ty, writable: b.writable }),
            }
        }
    }
    if problems.is_empty() {
        return Ok(layout);
    }
    Err(Error::Bug(format!("pipeline `{pipeline}`: its shaders' bindings make no set layout: {}", problems.join("; "))))
}

/// The last component of a `/` or `\` separated path.
fn file_name(path: &str) -> String {
    path.rsplit(['/', '\\']).next().unwrap_or(path).to_string()
}

/// The types a descriptor's variable may point at, and what classifies them.
#[derive(Clone, Copy, Debug)]
enum Type {
    /// `Sampled` is 1 for an image read through a sampler, 2 for a storage image.
    Image {
        dim: u32,
        sampled: u32,
    },
    Sampler,
    SampledImage {
        image: u32,
    },
    Array {
        element: u32,
        length: u32,
    },
    RuntimeArray {
        element: u32,
    },
    Struct {
        members: u32,
    },
    Pointer {
        pointee: u32,
    },
    AccelerationStructure,
}

/// A module-scope variable.
struct Variable {
    id: u32,
    ty: u32,
    class: u32,
}

/// What the instructions of a module say about ids: the part reflection needs.
#[derive(Default)]
struct Tables {
    names: HashMap<u32, String>,
    strings: HashMap<u32, String>,
    source_file: Option<u32>,
    bindings: HashMap<u32, u32>,
    sets: HashMap<u32, u32>,
    /// `Block` or `BufferBlock`, by struct type.
    blocks: HashMap<u32, Decoration>,
    /// The ids decorated `NonWritable`.
    non_writable: HashSet<u32>,
    /// The (struct type, member) pairs decorated `NonWritable`.
    non_writable_members: HashSet<(u32, u32)>,
    types: HashMap<u32, Type>,
    /// The value (first word) of each scalar constant and the default of each specialisation
    /// constant: what an array type's length refers to.
    constants: HashMap<u32, u32>,
    variables: Vec<Variable>,
}

impl Tables {
    /// Reads every instruction after the five-word header.
    fn read(words: &[u32]) -> std::result::Result<Tables, Malformed> {
        if words.len() < 5 {
            return Err(Malformed(format!("{} words, shorter than the header", words.len())));
        }
        let mut tables = Tables::default();
        let mut at = 5;
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            let opcode = words[at] & 0xffff;
            if count == 0 || at + count > words.len() {
                return Err(Malformed(format!("instruction at word {at} (opcode {opcode}) runs past the end")));
            }
            if let Some(op) = Op::from_u32(opcode) {
                tables.note(op, &words[at + 1..at + count])?;
            }
            at += count;
        }
        Ok(tables)
    }

    /// Notes one instruction with operands `ops` (ignores those reflection does not need).
    fn note(&mut self, op: Op, ops: &[u32]) -> std::result::Result<(), Malformed> {
        let word = |i: usize| ops.get(i).copied().ok_or_else(|| Malformed(format!("Op{op:?} lacks operand {i}")));
        match op {
            Op::Name => {
                self.names.insert(word(0)?, string(&ops[1..]));
            }
            Op::String => {
                self.strings.insert(word(0)?, string(&ops[1..]));
            }
            Op::Source if ops.len() > 2 && self.source_file.is_none() => self.source_file = Some(ops[2]),
            Op::Decorate => self.decorate(word(0)?, word(1)?, ops.get(2).copied()),
            Op::MemberDecorate if Decoration::from_u32(word(2)?) == Some(Decoration::NonWritable) => {
                self.non_writable_members.insert((word(0)?, word(1)?));
            }
            Op::TypeImage => {
                self.types.insert(word(0)?, Type::Image { dim: word(2)?, sampled: word(6)? });
            }
            Op::TypeSampler => {
                self.types.insert(word(0)?, Type::Sampler);
            }
            Op::TypeSampledImage => {
                self.types.insert(word(0)?, Type::SampledImage { image: word(1)? });
            }
            Op::TypeArray => {
                self.types.insert(word(0)?, Type::Array { element: word(1)?, length: word(2)? });
            }
            Op::TypeRuntimeArray => {
                self.types.insert(word(0)?, Type::RuntimeArray { element: word(1)? });
            }
            Op::TypeStruct => {
                self.types.insert(word(0)?, Type::Struct { members: ops.len().saturating_sub(1) as u32 });
            }
            Op::TypePointer => {
                self.types.insert(word(0)?, Type::Pointer { pointee: word(2)? });
            }
            Op::TypeAccelerationStructureKHR => {
                self.types.insert(word(0)?, Type::AccelerationStructure);
            }
            Op::Constant | Op::SpecConstant => {
                self.constants.insert(word(1)?, word(2)?);
            }
            Op::Variable => self.variables.push(Variable { ty: word(0)?, id: word(1)?, class: word(2)? }),
            _ => {}
        }
        Ok(())
    }

    fn decorate(&mut self, target: u32, decoration: u32, literal: Option<u32>) {
        match (Decoration::from_u32(decoration), literal) {
            (Some(Decoration::Binding), Some(n)) => {
                self.bindings.insert(target, n);
            }
            (Some(Decoration::DescriptorSet), Some(n)) => {
                self.sets.insert(target, n);
            }
            (Some(d @ (Decoration::Block | Decoration::BufferBlock)), _) => {
                self.blocks.insert(target, d);
            }
            (Some(Decoration::NonWritable), _) => {
                self.non_writable.insert(target);
            }
            _ => {}
        }
    }

    /// The binding `var` is, or `None` for a variable that is no descriptor (push constants,
    /// inputs, a function's locals) or carries no binding number.
    fn descriptor(&self, var: &Variable) -> std::result::Result<Option<ShaderBinding>, Malformed> {
        let class = StorageClass::from_u32(var.class);
        if !matches!(class, Some(StorageClass::UniformConstant | StorageClass::Uniform | StorageClass::StorageBuffer)) {
            return Ok(None);
        }
        let Some(&binding) = self.bindings.get(&var.id) else { return Ok(None) };
        let name = self.names.get(&var.id).cloned().unwrap_or_default();
        let what = || format!("binding {binding} (`{name}`)");
        let pointee = match self.types.get(&var.ty) {
            Some(&Type::Pointer { pointee }) => pointee,
            _ => return Err(Malformed(format!("{}: the variable's type is no pointer", what()))),
        };
        let (element, count) = match self.types.get(&pointee) {
            Some(&Type::Array { element, length }) => match self.constants.get(&length) {
                Some(&n) => (element, n),
                None => return Err(Malformed(format!("{}: an array of no constant length", what()))),
            },
            Some(&Type::RuntimeArray { element }) => (element, 0),
            _ => (pointee, 1),
        };
        let ty = self.descriptor_type(class, element).ok_or_else(|| {
            Malformed(format!("{}: no descriptor type for a {class:?} variable of this type", what()))
        })?;
        let set = self.sets.get(&var.id).copied().unwrap_or(0);
        let writable = self.writable(var.id, element, ty);
        Ok(Some(ShaderBinding { set, binding, ty, count, name, writable }))
    }

    /// Whether variable `var` of descriptor type `ty`, whose type (arrays taken off) is `element`,
    /// may be written: a storage type, without `NonWritable` on the variable nor on every member of
    /// its block.
    fn writable(&self, var: u32, element: u32, ty: vk::DescriptorType) -> bool {
        use vk::DescriptorType as D;
        if !matches!(ty, D::STORAGE_BUFFER | D::STORAGE_IMAGE | D::STORAGE_TEXEL_BUFFER)
            || self.non_writable.contains(&var)
        {
            return false;
        }
        match self.types.get(&element) {
            Some(&Type::Struct { members }) => (0..members).any(|m| !self.non_writable_members.contains(&(element, m))),
            _ => true,
        }
    }

    /// The descriptor type of a variable of storage class `class` whose type (arrays taken off)
    /// is `ty`, after the Vulkan specification's table "Shader Resource and Descriptor Type
    /// Correspondence".
    fn descriptor_type(&self, class: Option<StorageClass>, ty: u32) -> Option<vk::DescriptorType> {
        use vk::DescriptorType as D;
        let image = |dim: u32, sampled: u32| match (Dim::from_u32(dim), sampled) {
            (Some(Dim::DimBuffer), 2) => D::STORAGE_TEXEL_BUFFER,
            (Some(Dim::DimBuffer), _) => D::UNIFORM_TEXEL_BUFFER,
            (Some(Dim::DimSubpassData), _) => D::INPUT_ATTACHMENT,
            (_, 2) => D::STORAGE_IMAGE,
            _ => D::SAMPLED_IMAGE,
        };
        match (class?, *self.types.get(&ty)?) {
            (StorageClass::StorageBuffer, Type::Struct { .. }) => Some(D::STORAGE_BUFFER),
            (StorageClass::Uniform, Type::Struct { .. }) => match self.blocks.get(&ty)? {
                Decoration::BufferBlock => Some(D::STORAGE_BUFFER),
                _ => Some(D::UNIFORM_BUFFER),
            },
            (StorageClass::UniformConstant, Type::Sampler) => Some(D::SAMPLER),
            (StorageClass::UniformConstant, Type::Image { dim, sampled }) => Some(image(dim, sampled)),
            (StorageClass::UniformConstant, Type::SampledImage { image: of }) => match self.types.get(&of)? {
                Type::Image { dim, .. } if Dim::from_u32(*dim) == Some(Dim::DimBuffer) => Some(D::UNIFORM_TEXEL_BUFFER),
                Type::Image { .. } => Some(D::COMBINED_IMAGE_SAMPLER),
                _ => None,
            },
            (StorageClass::UniformConstant, Type::AccelerationStructure) => Some(D::ACCELERATION_STRUCTURE_KHR),
            _ => None,
        }
    }
}

/// A SPIR-V literal string: UTF-8 bytes, four to a word from the low byte, ending at a zero byte.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

#[cfg(test)]
mod tests;
