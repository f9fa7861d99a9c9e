//! Reflection on the shaders compiled into the crate and on small modules assembled here, and the
//! set layouts made of every pass's shaders: no device needed.

use ash::vk;
use spirv::{Decoration, Dim, Op, StorageClass};

use super::{layout, reflect, ShaderBinding};

/// A pipeline's name and its shader modules.
type Shaders = (&'static str, Vec<&'static [u8]>);

/// An instruction of a module assembled here: its opcode and its operands.
type Instruction = (Op, Vec<u32>);

/// Every pipeline the renderer makes.
fn pipelines() -> Vec<Shaders> {
    vec![
        ("accumulate", vec![crate::spirv!("accumulate.comp")]),
        ("background", vec![crate::spirv!("background.comp")]),
        ("canvas", vec![crate::spirv!("canvas.comp")]),
        ("compact", vec![crate::spirv!("compact.comp")]),
        ("compensation", vec![crate::spirv!("compensation.comp")]),
        ("compose", vec![crate::spirv!("compose.comp")]),
        ("denoise", vec![crate::spirv!("denoise.comp")]),
        ("denoise-sparse", vec![crate::spirv!("denoise_sparse.comp")]),
        ("diffuse", vec![crate::spirv!("diffuse.comp")]),
        ("eval", vec![crate::spirv!("eval.comp")]),
        ("gbuffer", vec![crate::spirv!("gbuffer.vert"), crate::spirv!("gbuffer.frag")]),
        ("lobe", vec![crate::spirv!("lobe.comp")]),
        ("mis", vec![crate::spirv!("mis.comp")]),
        ("peak", vec![crate::spirv!("peak.comp")]),
        ("zero", vec![crate::spirv!("zero.comp")]),
    ]
}

#[test]
fn every_pass_makes_its_layout_from_its_shaders() {
    for (name, modules) in pipelines() {
        let made = layout(name, &modules).unwrap_or_else(|e| panic!("{e}"));
        // The G-buffer pass reads nothing through descriptors; every compute pass does, with no
        // binding number left out.
        assert_eq!(made.is_empty(), name == "gbuffer", "{name}: {made:?}");
        assert!(made.iter().all(Option::is_some), "{name}: {made:?}");
    }
}

#[test]
fn reflection_names_the_shader_file_and_its_variables() {
    let r = reflect(crate::spirv!("compact.comp")).unwrap();
    assert_eq!(r.source.as_deref(), Some("compact.comp"));
    let env = &r.bindings[4];
    assert_eq!((env.set, env.binding, env.ty, env.count), (0, 4, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1));
    assert_eq!(env.name, "env_tex");
    let numbers: Vec<u32> = r.bindings.iter().map(|b| b.binding).collect();
    assert_eq!(numbers, (0..8).collect::<Vec<_>>());
}

#[test]
fn lobe_keeps_the_bindings_only_a_specialisation_reads() {
    // `light_set` (binding 7, a uniform block) is read only with LIGHTS on, a specialisation
    // constant; the optimiser cannot know it and keeps it.
    let r = reflect(crate::spirv!("lobe.comp")).unwrap();
    let light_set = r.bindings.iter().find(|b| b.binding == 7).expect("binding 7");
    assert_eq!(light_set.ty, vk::DescriptorType::UNIFORM_BUFFER);
}

#[test]
fn stages_that_disagree_on_a_binding_are_reported_with_shader_and_binding() {
    let storage_image = module(StorageClass::UniformConstant, 0, 2, 5, &[image(Dim::Dim2D, 2)]);
    let sampled_image = module(StorageClass::UniformConstant, 0, 2, 5, &[image(Dim::Dim2D, 1)]);
    let e = layout("two-stages", &[&storage_image, &sampled_image]).unwrap_err().to_string();
    assert!(e.contains("pipeline `two-stages`"), "{e}");
    assert!(e.contains("binding 2: SAMPLED_IMAGE here, STORAGE_IMAGE in another stage"), "{e}");
    // The same binding in two stages is one, writable where either may write it.
    let mut readonly = vec![image(Dim::Dim2D, 2)];
    readonly.push((Op::Decorate, vec![10, Decoration::NonWritable as u32]));
    let read = module(StorageClass::UniformConstant, 0, 2, 5, &readonly);
    let made = layout("two-stages", &[&read, &storage_image]).unwrap();
    assert_eq!(made.len(), 3);
    assert_eq!(made[2].map(|d| (d.ty, d.writable)), Some((vk::DescriptorType::STORAGE_IMAGE, true)));
}

#[test]
fn binding_numbers_no_shader_holds_are_left_out_of_the_layout() {
    let only_two = module(StorageClass::UniformConstant, 0, 2, 5, &[image(Dim::Dim2D, 2)]);
    let made = layout("gap", &[&only_two]).unwrap();
    assert_eq!(made[..2], [None, None]);
    assert!(made[2].is_some());
}

#[test]
fn a_graphics_pipeline_reads_each_stage() {
    let modules: [&[u8]; 2] = [crate::spirv!("gbuffer.vert"), crate::spirv!("gbuffer.frag")];
    let sampler = module(StorageClass::UniformConstant, 1, 0, 5, &[(Op::TypeSampler, vec![5])]);
    assert!(layout("gbuffer-test", &modules).unwrap().is_empty());
    let e = layout("gbuffer-test", &[modules[0], &sampler]).unwrap_err().to_string();
    assert!(e.contains("shader gbuffer-test, binding 0: in set 1, a pipeline has set 0 alone"), "{e}");
}

#[test]
fn malformed_modules_are_errors() {
    let good = crate::spirv!("zero.comp");
    // The header and the first word of `OpCapability`, which says it has two.
    assert!(reflect(&good[..24]).is_err(), "cut short");
    assert!(reflect(&good[..good.len() - 2]).is_err(), "not whole words");
    assert!(reflect(&good[4..]).is_err(), "no magic number");
    assert!(reflect(&good[..12]).is_err(), "shorter than the header");
    let mut zero_count = good[..20].to_vec();
    zero_count.extend_from_slice(&[0, 0, 0, 0]);
    assert!(reflect(&zero_count).is_err(), "an instruction of no words");
    let e = layout("zero-test", &[&good[..24]]).unwrap_err();
    assert!(matches!(e, crate::Error::Bug(_)) && e.to_string().contains("pipeline `zero-test`"), "{e}");
}

/// A module with one variable (id 10) of storage class `class` at `set` and `binding`, pointing
/// at type `pointee`, which `types` define (ids 5 to 8; id 1 is `float`, 2 `uint`, 3 the `uint`
/// constant 4).
fn module(class: StorageClass, set: u32, binding: u32, pointee: u32, types: &[Instruction]) -> Vec<u8> {
    let mut body = vec![
        (Op::Decorate, vec![10, Decoration::DescriptorSet as u32, set]),
        (Op::Decorate, vec![10, Decoration::Binding as u32, binding]),
        (Op::TypeFloat, vec![1, 32]),
        (Op::TypeInt, vec![2, 32, 0]),
        (Op::Constant, vec![2, 3, 4]),
    ];
    body.extend(types.iter().cloned());
    body.push((Op::TypePointer, vec![9, class as u32, pointee]));
    body.push((Op::Variable, vec![9, 10, class as u32]));
    let mut words = vec![spirv::MAGIC_NUMBER, 0x0001_0600, 0, 11, 0];
    for (op, ops) in body {
        words.push(((ops.len() as u32 + 1) << 16) | op as u32);
        words.extend(ops);
    }
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// `OpTypeImage` id 5 of `float` with dimension `dim` and `sampled` (1 sampled, 2 storage).
fn image(dim: Dim, sampled: u32) -> Instruction {
    (Op::TypeImage, vec![5, 1, dim as u32, 0, 0, 0, sampled, 0])
}

/// The one binding of a module from [`module`] at set 0, binding 2.
fn one(class: StorageClass, pointee: u32, types: &[Instruction]) -> ShaderBinding {
    let r = reflect(&module(class, 0, 2, pointee, types)).unwrap();
    assert_eq!(r.source, None);
    assert_eq!(r.bindings.len(), 1);
    r.bindings[0].clone()
}

#[test]
fn each_kind_of_resource_has_its_descriptor_type() {
    use vk::DescriptorType as D;
    use StorageClass::{StorageBuffer, Uniform, UniformConstant};
    let block = |d: Decoration| vec![(Op::TypeStruct, vec![5, 1]), (Op::Decorate, vec![5, d as u32])];
    let cases: Vec<(StorageClass, u32, Vec<Instruction>, D)> = vec![
        (UniformConstant, 5, vec![(Op::TypeSampler, vec![5])], D::SAMPLER),
        (UniformConstant, 6, vec![image(Dim::Dim2D, 1), (Op::TypeSampledImage, vec![6, 5])], D::COMBINED_IMAGE_SAMPLER),
        (UniformConstant, 5, vec![image(Dim::DimCube, 1)], D::SAMPLED_IMAGE),
        (UniformConstant, 5, vec![image(Dim::Dim2D, 2)], D::STORAGE_IMAGE),
        (UniformConstant, 5, vec![image(Dim::DimBuffer, 1)], D::UNIFORM_TEXEL_BUFFER),
        (UniformConstant, 5, vec![image(Dim::DimBuffer, 2)], D::STORAGE_TEXEL_BUFFER),
        (UniformConstant, 5, vec![image(Dim::DimSubpassData, 2)], D::INPUT_ATTACHMENT),
        (UniformConstant, 5, vec![(Op::TypeAccelerationStructureKHR, vec![5])], D::ACCELERATION_STRUCTURE_KHR),
        (Uniform, 5, block(Decoration::Block), D::UNIFORM_BUFFER),
        (Uniform, 5, block(Decoration::BufferBlock), D::STORAGE_BUFFER),
        (StorageBuffer, 5, block(Decoration::Block), D::STORAGE_BUFFER),
    ];
    for (class, pointee, types, want) in cases {
        let b = one(class, pointee, &types);
        assert_eq!((b.set, b.binding, b.ty, b.count), (0, 2, want, 1), "{class:?} {types:?}");
    }
}

#[test]
fn arrays_of_descriptors_are_counted_and_refused() {
    let sized = [image(Dim::Dim2D, 2), (Op::TypeArray, vec![6, 5, 3])];
    let b = one(StorageClass::UniformConstant, 6, &sized);
    assert_eq!((b.ty, b.count), (vk::DescriptorType::STORAGE_IMAGE, 4));
    let runtime = [image(Dim::Dim2D, 1), (Op::TypeRuntimeArray, vec![6, 5])];
    assert_eq!(one(StorageClass::UniformConstant, 6, &runtime).count, 0);
    let m = module(StorageClass::UniformConstant, 0, 2, 6, &sized);
    let e = layout("array-test", &[&m]).unwrap_err().to_string();
    assert!(e.contains("shader array-test, binding 2: an array of 4 descriptors, a binding holds one"), "{e}");
}

#[test]
fn variables_that_are_no_descriptors_are_left_out() {
    let push = module(StorageClass::PushConstant, 0, 0, 5, &[(Op::TypeStruct, vec![5, 1])]);
    assert!(reflect(&push).unwrap().bindings.is_empty());
}

#[test]
fn a_resource_of_unknown_type_is_an_error() {
    let e = reflect(&module(StorageClass::UniformConstant, 0, 1, 1, &[])).unwrap_err().to_string();
    assert!(e.contains("binding 1"), "{e}");
}

#[test]
fn readonly_storage_is_not_writable_and_plain_storage_is() {
    use StorageClass::{StorageBuffer, Uniform, UniformConstant};
    let non_writable = Decoration::NonWritable as u32;
    let storage_image = || vec![image(Dim::Dim2D, 2)];
    let mut readonly_image = storage_image();
    readonly_image.push((Op::Decorate, vec![10, non_writable]));
    // A block of two members, `readonly` as glslang writes it: on every member.
    let block = |readonly: &[u32]| {
        let mut types = vec![(Op::TypeStruct, vec![5, 1, 2]), (Op::Decorate, vec![5, Decoration::Block as u32])];
        types.extend(readonly.iter().map(|&m| (Op::MemberDecorate, vec![5, m, non_writable])));
        types
    };
    let cases: Vec<(&str, StorageClass, Vec<Instruction>, bool)> = vec![
        ("storage image", UniformConstant, storage_image(), true),
        ("readonly storage image", UniformConstant, readonly_image, false),
        ("storage buffer", StorageBuffer, block(&[]), true),
        ("readonly storage buffer", StorageBuffer, block(&[0, 1]), false),
        ("storage buffer with one readonly member", StorageBuffer, block(&[1]), true),
        ("uniform buffer", Uniform, block(&[]), false),
        ("sampled image", UniformConstant, vec![image(Dim::Dim2D, 1)], false),
    ];
    for (what, class, types, writable) in cases {
        assert_eq!(one(class, 5, &types).writable, writable, "{what}");
    }
}

#[test]
fn each_pass_may_write_the_bindings_its_glsl_leaves_writable() {
    // Per binding: `w` where the shader may write it (not `readonly`), `-` where it may not
    // (`readonly`, a uniform buffer, a sampler).
    let expected = [
        ("accumulate", "-w"),
        ("background", "-w--"),
        ("canvas", "w--"),
        ("compact", "-www---w"),
        ("compensation", "-w------"),
        ("compose", "w--"),
        ("denoise", "-ww"),
        ("denoise-sparse", "-w-----"),
        ("diffuse", "-w---"),
        ("eval", "-w--"),
        ("gbuffer", ""),
        ("lobe", "-w-------w"),
        ("mis", "-w--------"),
        ("peak", "w"),
        ("zero", "ww"),
    ];
    let pipelines = pipelines();
    assert_eq!(pipelines.len(), expected.len());
    for ((name, modules), (want_name, want)) in pipelines.into_iter().zip(expected) {
        assert_eq!(name, want_name);
        let made = layout(name, &modules).unwrap();
        let got: String = made.iter().map(|d| if d.is_some_and(|d| d.writable) { 'w' } else { '-' }).collect();
        assert_eq!(got, want, "{name}");
    }
}

#[test]
fn lobe_reads_its_normals_and_writes_its_accumulation() {
    let r = reflect(crate::spirv!("lobe.comp")).unwrap();
    let named = |n: u32| r.bindings.iter().find(|b| b.binding == n).expect("a binding");
    assert_eq!((named(0).name.as_str(), named(0).writable), ("gnrm", false));
    assert_eq!((named(1).name.as_str(), named(1).writable), ("accum", true));
    assert_eq!((named(4).name.as_str(), named(4).writable), ("halton", false));
}
