//! Compiles every GLSL 450 stage in `shaders/` (`*.vert`, `*.frag`, `*.comp`) to SPIR-V with naga (no shaderc or
//! glslang). `#include "file.glsl"` lines are spliced here, since naga's GLSL front end has no `#include`.
//! A parse or validation error fails the build with the file, the line and naga's message.

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

/// Variants of the march shaders: (suffix, defines), in the order of `render::march_variant`'s indices.
/// lavapipe pays for code under an untaken `if` that samples textures, so each compositing family and the
/// shading path get their own SPIR-V (see shaders/march.glsl, which needs one FAMILY_ define).
const MARCH_VARIANTS: &[(&str, &[&str])] = &[
    ("ea", &["FAMILY_EMISSION"]),
    ("ea_shaded", &["FAMILY_EMISSION", "SHADED"]),
    ("proj", &["FAMILY_PROJECTION"]),
    ("iso", &["FAMILY_ISOSURFACE"]),
    ("ea_shaded_tex", &["FAMILY_EMISSION", "SHADED", "GRADIENT_TEXTURE"]),
    ("iso_tex", &["FAMILY_ISOSURFACE", "GRADIENT_TEXTURE"]),
    ("ea_shaded_lv", &["FAMILY_EMISSION", "SHADED", "LIGHT_VOLUME"]),
    ("ea_shaded_tex_lv", &["FAMILY_EMISSION", "SHADED", "GRADIENT_TEXTURE", "LIGHT_VOLUME"]),
    ("iso_lv", &["FAMILY_ISOSURFACE", "LIGHT_VOLUME"]),
    ("iso_tex_lv", &["FAMILY_ISOSURFACE", "GRADIENT_TEXTURE", "LIGHT_VOLUME"]),
];

/// How the march reads the volume, in the order of `render::VolumeLayout::index`: a 3D texture, or the corner
/// buffers of 8- and 16-bit data (see `render::VolumeLayout`).
const SAMPLINGS: &[(&str, &[&str])] = &[("", &[]), ("_c8", &["CORNERS8"]), ("_c16", &["CORNERS16"])];

/// The march shader files, in the order of `render::setup_index`.
const MARCH_FILES: &[&str] = &["march_faces.frag", "march_analytic.frag", "march_compute.comp"];

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
            SAMPLINGS
                .iter()
                .map(|(sampling, defines)| (format!("light.comp{sampling}"), defines.to_vec()))
                .collect()
        } else if name.starts_with("march_") {
            let name = &name;
            MARCH_VARIANTS
                .iter()
                .flat_map(|(suffix, defines)| {
                    SAMPLINGS.iter().map(move |(sampling, more)| {
                        let all: Vec<&str> = defines.iter().chain(more.iter()).copied().collect();
                        (format!("{name}.{suffix}{sampling}"), all)
                    })
                })
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
    // The table of march shaders the renderer indexes by [setup][variant][sampling].
    let mut table = format!(
        "/// March SPIR-V by [`setup_index`][`march_variant`][`VolumeLayout::index`] (written by build.rs).\n\
         pub(crate) const MARCH_SHADERS: [[[ShaderCode; 3]; {}]; 3] = [\n",
        MARCH_VARIANTS.len()
    );
    for file in MARCH_FILES {
        table.push_str("    [\n");
        for (suffix, _) in MARCH_VARIANTS {
            table.push_str("        [\n");
            for (sampling, _) in SAMPLINGS {
                let name = format!("{file}.{suffix}{sampling}");
                let _ = writeln!(
                    table,
                    "            ShaderCode {{ name: \"{name}\", bytes: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}.spv\")) }},"
                );
            }
            table.push_str("        ],\n");
        }
        table.push_str("    ],\n");
    }
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
