//! Compiles every GLSL 450 stage in `shaders/` (`*.vert`, `*.frag`, `*.comp`) to SPIR-V with naga (no shaderc or
//! glslang). `#include "file.glsl"` lines are spliced here, since naga's GLSL front end has no `#include`.
//! The march files are compiled once per variant that src/render/march_key.rs lists, light.comp once per volume
//! layout, and a table of them written for the renderer. A parse or validation error fails the build with the
//! file, the line and naga's message.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Where each line of a spliced source came from, for error messages.
struct Spliced {
    text: String,
    origin: Vec<(PathBuf, usize)>,
}

fn splice(path: &Path, depth: usize, out: &mut Spliced) -> Result<(), String> {
    if depth > 8 {
        return Err(format!("{}: #include nested too deeply", path.display()));
    }
    println!("cargo:rerun-if-changed={}", path.display());
    let src = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    for (i, line) in src.lines().enumerate() {
        if let Some(rest) = line.trim_start().strip_prefix("#include") {
            let name = rest.trim().trim_matches('"');
            let inc = path.parent().unwrap_or(Path::new(".")).join(name);
            splice(&inc, depth + 1, out).map_err(|e| format!("{e}\n  included from {}:{}", path.display(), i + 1))?;
        } else {
            out.text.push_str(line);
            out.text.push('\n');
            out.origin.push((path.to_path_buf(), i + 1));
        }
    }
    Ok(())
}

// The march variants and the light pass's samplings: the same file the renderer indexes the table by.
#[allow(dead_code)] // build.rs needs the list, the names and the defines; the renderer the rest
#[path = "src/render/march_key.rs"]
mod march_key;
use march_key::{MarchKey, Sampling, Setup};

/// The SPIR-V name of light.comp compiled for `sampling`.
fn light_name(sampling: Sampling) -> String {
    format!("light.comp{}", sampling.suffix())
}

fn compile(path: &Path, stage: naga::ShaderStage, defines: &[&str]) -> Result<Vec<u32>, String> {
    let mut sp = Spliced {
        text: String::new(),
        origin: Vec::new(),
    };
    splice(path, 0, &mut sp)?;
    if !defines.is_empty() {
        // After the #version line, which must stay first.
        let first_len = sp.text.find('\n').map(|i| i + 1).unwrap_or(0);
        let inserted: String = defines.iter().map(|d| format!("#define {d}\n")).collect();
        sp.text.insert_str(first_len, &inserted);
        let at = sp.origin.len().min(1);
        for _ in defines {
            sp.origin.insert(at, (path.to_path_buf(), 0));
        }
    }
    let locate = |span: naga::Span| -> String {
        let loc = span.location(&sp.text);
        match sp.origin.get((loc.line_number as usize).saturating_sub(1)) {
            Some((file, line)) => format!("{}:{}:{}", file.display(), line, loc.line_position),
            None => format!("{}:?", path.display()),
        }
    };
    let mut frontend = naga::front::glsl::Frontend::default();
    let module = frontend
        .parse(&naga::front::glsl::Options::from(stage), &sp.text)
        .map_err(|errs| {
            let mut msg = String::new();
            for e in errs.errors.iter() {
                let _ = writeln!(msg, "{}: {}", locate(e.meta), e.kind);
            }
            msg
        })?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| {
            let mut msg = String::new();
            for (span, label) in e.spans() {
                let _ = writeln!(msg, "{}: {label}", locate(*span));
            }
            format!("{}: validation failed: {}\n{msg}", path.display(), e.as_inner())
        })?;
    // ADJUST_COORDINATE_SPACE would negate gl_Position.y, which also swaps triangle winding and so the entry and
    // exit passes. The projection (camera.rs) handles Vulkan's y-down clip space itself.
    let options = naga::back::spv::Options {
        flags: naga::back::spv::WriterFlags::DEBUG | naga::back::spv::WriterFlags::LABEL_VARYINGS,
        lang_version: (1, 3),
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: stage,
        entry_point: "main".into(),
    };
    naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| format!("{}: SPIR-V output failed: {e}", path.display()))
}

fn main() {
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed=shaders");
    println!("cargo:rerun-if-changed=src/render/march_key.rs");
    let mut entries: Vec<PathBuf> = std::fs::read_dir("shaders")
        .expect("shaders/ folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let mut failures = Vec::new();
    for path in entries {
        let stage = match path.extension().and_then(|e| e.to_str()) {
            Some("vert") => naga::ShaderStage::Vertex,
            Some("frag") => naga::ShaderStage::Fragment,
            Some("comp") => naga::ShaderStage::Compute,
            _ => {
                println!("cargo:rerun-if-changed={}", path.display());
                continue;
            }
        };
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("utf-8 shader name")
            .to_string();
        let variants: Vec<(String, Vec<&str>)> = if name == "light.comp" {
            // Rule 9's light grid reads the volume as the march does, in every layout.
            Sampling::ALL
                .iter()
                .map(|&s| (light_name(s), s.defines().to_vec()))
                .collect()
        } else if let Some(setup) = Setup::ALL.into_iter().find(|s| s.file() == name) {
            MarchKey::all()
                .filter(|k| k.setup == setup)
                .map(|k| (k.name(), k.defines()))
                .collect()
        } else {
            vec![(name.clone(), Vec::new())]
        };
        for (out_name, defines) in variants {
            match compile(&path, stage, &defines) {
                Ok(words) => {
                    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                    std::fs::write(out_dir.join(format!("{out_name}.spv")), bytes).expect("write SPIR-V to OUT_DIR");
                }
                Err(e) => failures.push(format!("{e} (variant {out_name})")),
            }
        }
    }
    // The tables the renderer indexes by `MarchKey::index` and `Sampling::index`.
    let entry = |name: &str| {
        format!("    ShaderCode {{ name: \"{name}\", bytes: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}.spv\")) }},\n")
    };
    let mut table = String::from(
        "/// The march SPIR-V in `MarchKey::index` order (written by build.rs).\n\
         pub(crate) const MARCH_SHADERS: [ShaderCode; MarchKey::COUNT] = [\n",
    );
    table.extend(MarchKey::all().map(|k| entry(&k.name())));
    table.push_str(
        "];\n\n/// light.comp in `Sampling::index` order (written by build.rs).\n\
         pub(crate) const LIGHT_SHADERS: [ShaderCode; Sampling::ALL.len()] = [\n",
    );
    table.extend(Sampling::ALL.map(|s| entry(&light_name(s))));
    table.push_str("];\n");
    std::fs::write(out_dir.join("march_shaders.rs"), table).expect("write march_shaders.rs to OUT_DIR");
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("shader error: {f}");
        }
        panic!(
            "{} shader(s) failed to compile:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
}
