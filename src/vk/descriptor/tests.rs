//! The check of a list of resources against a pipeline's layout (its shaders' bindings), on lists
//! given as what each binding is written as (a type and whether it is passed read-only): no device
//! needed.

use ash::vk;

use super::{check_written, Declared};
use crate::vk::reflect;

const IMAGE: vk::DescriptorType = vk::DescriptorType::STORAGE_IMAGE;
const BUFFER: vk::DescriptorType = vk::DescriptorType::STORAGE_BUFFER;
const UNIFORM: vk::DescriptorType = vk::DescriptorType::UNIFORM_BUFFER;

/// A layout of a read-only image, a writable image, a read-only buffer and a uniform buffer.
fn layout() -> Vec<Option<Declared>> {
    vec![
        Some(Declared { ty: IMAGE, writable: false }),
        Some(Declared { ty: IMAGE, writable: true }),
        Some(Declared { ty: BUFFER, writable: false }),
        Some(Declared { ty: UNIFORM, writable: false }),
    ]
}

/// The error message of checking `written` against `declared`, as pipeline `test`.
fn error(declared: &[Option<Declared>], written: &[(vk::DescriptorType, bool)]) -> String {
    let e = check_written("test", declared, written.iter().copied()).expect_err("a mismatch");
    assert!(matches!(e, crate::Error::Bug(_)), "{e}");
    let e = e.to_string();
    assert!(e.contains("pipeline `test`"), "{e}");
    e
}

#[test]
fn a_list_that_matches_the_layout_passes() {
    let written = [(IMAGE, true), (IMAGE, false), (BUFFER, true), (UNIFORM, false)];
    check_written("test", &layout(), written.into_iter()).unwrap();
    // Passing writable what the shader only reads costs a barrier at most: allowed.
    let written = [(IMAGE, false), (IMAGE, false), (BUFFER, false), (UNIFORM, false)];
    check_written("test", &layout(), written.into_iter()).unwrap();
    check_written("test", &[], std::iter::empty()).unwrap();
}

#[test]
fn a_list_short_of_the_layout_is_refused() {
    let short = [(IMAGE, true), (IMAGE, false), (BUFFER, true)];
    let e = error(&layout(), &short);
    assert!(e.contains("3 bindings written, the shader has 4"), "{e}");
}

#[test]
fn resources_at_bindings_compiled_out_of_the_shader_are_allowed() {
    // Past the layout's last binding, and at a number the layout lacks: any type.
    let long = [(IMAGE, true), (IMAGE, false), (BUFFER, true), (UNIFORM, false), (IMAGE, false)];
    check_written("test", &layout(), long.into_iter()).unwrap();
    let mut gap = layout();
    gap[2] = None;
    let written = [(IMAGE, true), (IMAGE, false), (UNIFORM, true), (UNIFORM, false)];
    check_written("test", &gap, written.into_iter()).unwrap();
}

#[test]
fn a_binding_of_another_type_is_refused_with_both_types() {
    let written = [(IMAGE, true), (IMAGE, false), (UNIFORM, false), (UNIFORM, false)];
    let e = error(&layout(), &written);
    assert!(e.contains("binding 2: the shader has STORAGE_BUFFER, written UNIFORM_BUFFER"), "{e}");
    assert!(!e.contains("binding 3"), "{e}");
}

#[test]
fn a_read_only_binding_the_shader_may_write_is_refused() {
    let written = [(IMAGE, true), (IMAGE, true), (BUFFER, true), (UNIFORM, false)];
    let e = error(&layout(), &written);
    assert!(e.contains("binding 1: STORAGE_IMAGE written read-only, but the shader may write it"), "{e}");
    assert!(!e.contains("binding 0") && !e.contains("binding 2"), "{e}");
}

#[test]
fn the_accumulate_pass_list_is_checked_against_its_shader() {
    // As `accumulate.rs` writes it: the frame read-only, the sum writable.
    let declared = reflect::layout("accumulate", &[crate::spirv!("accumulate.comp")]).unwrap();
    check_written("accumulate", &declared, [(IMAGE, true), (IMAGE, false)].into_iter()).unwrap();
    let e = check_written("accumulate", &declared, [(IMAGE, true), (IMAGE, true)].into_iter()).unwrap_err();
    assert!(e.to_string().contains("binding 1: STORAGE_IMAGE written read-only"), "{e}");
}
