//! Compiles every `glsl/*.{vert,frag,comp}` to SPIR-V in `OUT_DIR` with shaderc (the system
//! `libshaderc` when installed). Includes resolve only from `glsl/include/`; every file read gets a
//! `cargo:rerun-if-changed`. No SPIR-V lives in the source tree.

use std::path::PathBuf;

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let glsl = root.join("glsl");
    let include = glsl.join("include");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    println!("cargo:rerun-if-changed={}", glsl.display());
    println!("cargo:rerun-if-changed={}", include.display());

    let compiler = shaderc::Compiler::new().expect("shaderc: no compiler");
    let mut failed = Vec::new();
    let mut entries: Vec<_> = std::fs::read_dir(&glsl).unwrap().filter_map(|e| e.ok()).map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let kind = match path.extension().and_then(|e| e.to_str()) {
            Some("vert") => shaderc::ShaderKind::Vertex,
            Some("frag") => shaderc::ShaderKind::Fragment,
            Some("comp") => shaderc::ShaderKind::Compute,
            _ => continue,
        };
        println!("cargo:rerun-if-changed={}", path.display());
        let source = std::fs::read_to_string(&path).unwrap();
        let mut options = shaderc::CompileOptions::new().unwrap();
        options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_3 as u32);
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_generate_debug_info();
        let inc = include.clone();
        options.set_include_callback(move |name, _ty, _from, _depth| {
            let file = inc.join(name);
            match std::fs::read_to_string(&file) {
                Ok(content) => {
                    println!("cargo:rerun-if-changed={}", file.display());
                    Ok(shaderc::ResolvedInclude { resolved_name: file.display().to_string(), content })
                }
                Err(e) => Err(format!("{}: {e} (includes come from glsl/include/ only)", file.display())),
            }
        });
        let name = path.file_name().unwrap().to_str().unwrap();
        match compiler.compile_into_spirv(&source, kind, &path.display().to_string(), "main", Some(&options)) {
            Ok(artifact) => {
                std::fs::write(out.join(format!("{name}.spv")), artifact.as_binary_u8()).unwrap();
            }
            Err(e) => failed.push(format!("{name}: {e}")),
        }
    }
    if !failed.is_empty() {
        panic!("shader compilation failed:\n{}", failed.join("\n"));
    }
}
