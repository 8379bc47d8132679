//! What lights a frame and what iso-surfaces are made of: the light (rule 5 of `RenderSettings`) and the
//! iso-surfaces' materials (rule 7). Pure data and validation; the GPU (shaders/march.glsl) and the CPU reference
//! (tests/common) implement the rules.

use glam::Vec3;

/// The most iso-surfaces one frame shows (the frame's uniform block holds four).
pub const MAX_ISOSURFACES: usize = 4;

/// A light neutral (sRGB): the default iso-surface material, light enough that any iso value reads as a surface.
pub const NEUTRAL: Vec3 = Vec3::new(0.9, 0.88, 0.84);

/// The light of rule 5.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Light {
    /// Unit direction towards the light in the render world (rule 0: RAS for anatomical volumes), fixed to the
    /// volume; `None`: a headlight, from the eye along each ray.
    pub direction: Option<Vec3>,
    /// sRGB in [0,1].
    pub color: Vec3,
    /// Scales the light's colour (the diffuse and specular terms; ambient is not the light's).
    pub intensity: f32,
}

impl Default for Light {
    fn default() -> Light {
        Light {
            direction: None,
            color: Vec3::ONE,
            intensity: 1.0,
        }
    }
}

impl Light {
    /// A directional light from azimuth and elevation in degrees, as `Camera::orbit` places an eye: azimuth about
    /// +z from +y (counter-clockwise), elevation above the xy plane.
    pub fn from_angles(azimuth_deg: f32, elevation_deg: f32) -> Light {
        let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        Light {
            direction: Some(Vec3::new(-a.sin() * e.cos(), a.cos() * e.cos(), e.sin())),
            ..Light::default()
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if let Some(d) = self.direction {
            if !(d.is_finite() && d.length() > 1e-6) {
                return Err(format!("light direction {d} must be a non-zero vector"));
            }
        }
        if !(self.color.cmpge(Vec3::ZERO).all() && self.color.cmple(Vec3::ONE).all()) {
            return Err(format!("light colour {} must be in [0,1] per channel", self.color));
        }
        if !(0.0..=16.0).contains(&self.intensity) {
            return Err(format!("light intensity {} must be in [0,16]", self.intensity));
        }
        Ok(())
    }
}

/// One iso-surface of rule 7.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct IsoSurface {
    /// Normalised value in [0,1].
    pub value: f32,
    /// sRGB material colour; `None`: the classification's colour at the value (rule 4, clamped into the window).
    pub color: Option<Vec3>,
    /// Opacity in (0,1]: 1 hides everything behind the surface.
    pub opacity: f32,
}

impl Default for IsoSurface {
    fn default() -> IsoSurface {
        IsoSurface {
            value: 0.5,
            color: Some(NEUTRAL),
            opacity: 1.0,
        }
    }
}

impl IsoSurface {
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.value) {
            return Err(format!("iso value {} must be in [0,1]", self.value));
        }
        if !(self.opacity > 0.0 && self.opacity <= 1.0) {
            return Err(format!("iso-surface opacity {} must be in (0,1]", self.opacity));
        }
        if let Some(c) = self.color {
            if !(c.cmpge(Vec3::ZERO).all() && c.cmple(Vec3::ONE).all()) {
                return Err(format!("iso-surface colour {c} must be in [0,1] per channel"));
            }
        }
        Ok(())
    }

    /// Parses `VALUE[,R,G,B|,colormap][,OPACITY]` as `--surface` takes it: `0.3`, `0.3,0.9,0.7,0.6`,
    /// `0.3,0.9,0.7,0.6,0.4`, `0.6,colormap` or `0.6,colormap,0.5`.
    pub fn parse(text: &str) -> Result<IsoSurface, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let number = |s: &str| {
            s.parse::<f32>()
                .map_err(|_| format!("surface '{text}': '{s}' is not a number"))
        };
        let mut surface = IsoSurface {
            value: number(parts[0])?,
            ..IsoSurface::default()
        };
        let rest = &parts[1..];
        let opacity = match rest {
            [] => None,
            ["colormap", tail @ ..] => {
                surface.color = None;
                match tail {
                    [] => None,
                    [a] => Some(*a),
                    _ => return Err(format!("surface '{text}': expected VALUE,colormap[,OPACITY]")),
                }
            }
            [r, g, b, tail @ ..] => {
                surface.color = Some(Vec3::new(number(r)?, number(g)?, number(b)?));
                match tail {
                    [] => None,
                    [a] => Some(*a),
                    _ => return Err(format!("surface '{text}': expected VALUE[,R,G,B][,OPACITY]")),
                }
            }
            _ => {
                return Err(format!(
                    "surface '{text}': expected VALUE, VALUE,R,G,B, VALUE,R,G,B,OPACITY or VALUE,colormap[,OPACITY]"
                ))
            }
        };
        if let Some(a) = opacity {
            surface.opacity = number(a)?;
        }
        surface.validate()?;
        Ok(surface)
    }
}

/// Orders `surfaces` as rule 7 composites them: by value, lowest first (the order a ray entering ever higher
/// values meets them).
pub fn sorted(surfaces: &[IsoSurface]) -> Vec<IsoSurface> {
    let mut v = surfaces.to_vec();
    v.sort_by(|a, b| a.value.total_cmp(&b.value));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surfaces_parse_in_every_documented_form() {
        assert_eq!(IsoSurface::parse("0.3").unwrap().value, 0.3);
        let s = IsoSurface::parse("0.3, 0.9,0.7,0.6").unwrap();
        assert_eq!((s.color, s.opacity), (Some(Vec3::new(0.9, 0.7, 0.6)), 1.0));
        assert_eq!(IsoSurface::parse("0.3,0.9,0.7,0.6,0.4").unwrap().opacity, 0.4);
        let c = IsoSurface::parse("0.6,colormap,0.5").unwrap();
        assert_eq!((c.color, c.opacity), (None, 0.5));
        for bad in [
            "",
            "x",
            "0.3,0.9",
            "1.5",
            "0.3,colormap,0",
            "0.3,2,0,0",
            "0.3,1,1,1,1,1",
        ] {
            assert!(IsoSurface::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn lights_validate_and_angles_point_where_the_camera_would_be() {
        let l = Light::from_angles(0.0, 90.0);
        assert!((l.direction.unwrap() - Vec3::Z).length() < 1e-6);
        let l = Light::from_angles(90.0, 0.0);
        assert!((l.direction.unwrap() + Vec3::X).length() < 1e-6);
        assert!(Light::default().validate().is_ok());
        let zero = Light {
            direction: Some(Vec3::ZERO),
            ..Light::default()
        };
        assert!(zero.validate().is_err());
        let bright = Light {
            intensity: 100.0,
            ..Light::default()
        };
        assert!(bright.validate().is_err());
    }
}
