//! Value parsers for clap (`value_parser = parse_*`): sizes, vectors, colours, lights, slabs, planes, named
//! values; their error texts are what a malformed value prints.

use crate::scene::quality::{Gradients, Quality};
use crate::scene::values::DataValue;
use glam::Vec3;

/// A memory size for --host-budget and --gpu-budget (`pyramid::budget::parse_size`).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    crate::pyramid::budget::parse_size(s)
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size '{s}' must look like 512x512"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size '{s}' must look like 512x512"))
    };
    Ok((p(w)?, p(h)?))
}

fn parse_floats(s: &str, n: usize, what: &str) -> Result<Vec<f32>, String> {
    let v: Result<Vec<f32>, _> = s.split(',').map(|x| x.trim().parse::<f32>()).collect();
    match v {
        Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(format!("'{s}' must be {n} comma-separated numbers ({what})")),
    }
}

pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    parse_floats(s, 3, "X,Y,Z").map(|v| Vec3::new(v[0], v[1], v[2]))
}

/// `--iso-color`: a colour or the classification's.
#[derive(Clone, Copy, Debug)]
pub enum IsoColor {
    Colormap,
    Rgb(Vec3),
}

pub fn parse_iso_color(s: &str) -> Result<IsoColor, String> {
    if s.trim().eq_ignore_ascii_case("colormap") {
        return Ok(IsoColor::Colormap);
    }
    parse_floats(s, 3, "R,G,B or colormap").map(|v| IsoColor::Rgb(Vec3::new(v[0], v[1], v[2])))
}

/// `--surface VALUE,...`: the value in data units or a percentage (placed in the range once the volume is read),
/// and the rest of the surface.
pub fn parse_surface(s: &str) -> Result<(DataValue, crate::scene::lighting::IsoSurface), String> {
    let (value, rest) = s.split_once(',').map_or((s, None), |(v, r)| (v, Some(r)));
    let value = DataValue::parse(value).map_err(|e| format!("surface '{s}': {e}"))?;
    let surface = crate::scene::lighting::IsoSurface::parse(&match rest {
        Some(r) => format!("0,{r}"),
        None => "0".into(),
    })
    .map_err(|e| e.replacen("'0,", &format!("'{}", s.split(',').next().unwrap_or("")), 1))?;
    Ok((value, surface))
}

/// `--light`: a headlight (None) or a direction towards the light.
#[derive(Clone, Copy, Debug)]
pub struct LightDirection(pub Option<Vec3>);

pub fn parse_light(s: &str) -> Result<LightDirection, String> {
    if s.trim().eq_ignore_ascii_case("head") {
        return Ok(LightDirection(None));
    }
    parse_vec3(s).map(|d| LightDirection(Some(d)))
}

pub fn parse_pair(s: &str) -> Result<(f32, f32), String> {
    parse_floats(s, 2, "TMIN,TMAX").map(|v| (v[0], v[1]))
}

/// `--window LO,HI`: two values in data units or percentages of the range.
pub fn parse_window(s: &str) -> Result<(DataValue, DataValue), String> {
    match s.split(',').map(DataValue::parse).collect::<Result<Vec<_>, _>>()?[..] {
        [lo, hi] => Ok((lo, hi)),
        _ => Err(format!(
            "'{s}' must be two values LO,HI (data units, or percentages such as 10%,90%)"
        )),
    }
}

pub fn parse_data_value(s: &str) -> Result<DataValue, String> {
    DataValue::parse(s)
}

pub fn parse_shading(s: &str) -> Result<crate::scene::settings::Shading, String> {
    let v = parse_floats(s, 4, "AMBIENT,DIFFUSE,SPECULAR,SHININESS")?;
    Ok(crate::scene::settings::Shading {
        ambient: v[0],
        diffuse: v[1],
        specular: v[2],
        shininess: v[3],
    })
}

pub fn parse_clip_plane(s: &str) -> Result<crate::scene::clip::ClipPlane, String> {
    crate::scene::clip::ClipPlane::parse(s).map_err(|e| e.to_string())
}

pub fn parse_slice(s: &str) -> Result<(usize, f32, f32), String> {
    let parts: Vec<&str> = s.split(':').collect();
    let bad = || format!("slice '{s}' must look like x:0.5:0.2 (axis x|y|z, position, width in [0,1])");
    if parts.len() != 3 {
        return Err(bad());
    }
    let axis = match parts[0].trim() {
        "x" | "X" => 0,
        "y" | "Y" => 1,
        "z" | "Z" => 2,
        _ => return Err(bad()),
    };
    let pos: f32 = parts[1].trim().parse().map_err(|_| bad())?;
    let width: f32 = parts[2].trim().parse().map_err(|_| bad())?;
    if !((0.0..=1.0).contains(&pos) && width > 0.0 && width <= 1.0) {
        return Err(bad());
    }
    Ok((axis, pos, width))
}

/// " (did you mean 'NAME'?)" for the name in `names` nearest a misspelled `s`, as clap suggests flags: Jaro
/// similarity above 0.7 (clap's threshold), else nothing.
pub fn did_you_mean(s: &str, names: &[&str]) -> String {
    let s = s.trim().to_ascii_lowercase();
    names
        .iter()
        .map(|n| (strsim::jaro(&s, n), n))
        .filter(|(score, _)| *score > 0.7)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, n)| format!(" (did you mean '{n}'?)"))
        .unwrap_or_default()
}

/// `parse(s)`, or an error listing the names of `all` (`what` says what the value is).
fn parse_named<T: Copy>(
    s: &str,
    parse: fn(&str) -> Option<T>,
    all: &[T],
    name: fn(T) -> &'static str,
    what: &str,
) -> Result<T, String> {
    parse(s).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|&v| name(v)).collect();
        format!(
            "unknown {what} '{s}'{}; choose one of {}",
            did_you_mean(s, &names),
            names.join(", ")
        )
    })
}

/// `--turntable`'s frame count.
pub fn parse_turntable(s: &str) -> Result<u32, String> {
    let max = crate::movie::MAX_FRAMES;
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("a turntable has 1 to {max} frames")),
    }
}

/// `--fps`: a GIF's frame rate.
pub fn parse_fps(s: &str) -> Result<f32, String> {
    let fps = s
        .trim()
        .parse::<f32>()
        .map_err(|_| format!("'{s}' is not a number of frames per second"))?;
    crate::movie::gif::check_fps(fps).map(|()| fps)
}

/// `--gradients`' value, for render and bench alike.
pub fn parse_gradients(s: &str) -> Result<Gradients, String> {
    parse_named(s, Gradients::parse, &Gradients::ALL, Gradients::name, "gradient source")
}

/// `--quality`'s value, for render, view and bench alike.
pub fn parse_quality(s: &str) -> Result<Quality, String> {
    parse_named(s, Quality::parse, &Quality::ALL, Quality::name, "quality")
}

/// `--colormap`: a colormap's name.
pub fn parse_colormap(s: &str) -> Result<crate::transfer::Colormap, String> {
    use crate::transfer::Colormap;
    parse_named(s, Colormap::parse, &Colormap::ALL, Colormap::name, "colormap")
}

/// `--mode`: a compositing mode's name.
pub fn parse_mode(s: &str) -> Result<crate::scene::settings::CompositeMode, String> {
    use crate::scene::settings::CompositeMode;
    parse_named(
        s,
        CompositeMode::parse,
        &CompositeMode::ALL,
        CompositeMode::name,
        "mode",
    )
}

/// `--overlay-blend`: how overlays meet the rest (rule 13).
pub fn parse_blend(s: &str) -> Result<crate::scene::layers::Blend, String> {
    use crate::scene::layers::Blend;
    parse_named(s, Blend::parse, &Blend::ALL, Blend::name, "blend")
}

/// `--view`: a side of the patient.
pub fn parse_view(s: &str) -> Result<crate::scene::camera::ViewPreset, String> {
    use crate::scene::camera::ViewPreset;
    parse_named(s, ViewPreset::parse, &ViewPreset::ALL, ViewPreset::name, "view")
}

/// `--preset`: a preset's name or "auto" (kept as text: `auto` needs the volume to become a function).
pub fn parse_preset(s: &str) -> Result<String, String> {
    let name = s.trim();
    if name == "auto" || crate::transfer::function::PRESET_NAMES.contains(&name) {
        Ok(name.to_string())
    } else {
        let names = crate::transfer::function::PRESET_NAMES;
        Err(format!(
            "unknown preset '{name}'{}; choose one of {}, auto",
            did_you_mean(name, &[names, &["auto"][..]].concat()),
            names.join(", ")
        ))
    }
}

/// `--builtin`: a built-in volume's name.
pub fn parse_builtin(s: &str) -> Result<String, String> {
    let names = crate::volume::BUILTIN_NAMES;
    names.contains(&s.trim()).then(|| s.trim().to_string()).ok_or_else(|| {
        format!(
            "unknown built-in volume '{s}'{}; choose one of {}",
            did_you_mean(s, names),
            names.join(", ")
        )
    })
}
