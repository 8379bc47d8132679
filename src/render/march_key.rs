//! The compiled variants of the march. lavapipe executes both sides of every `if` (an untaken shading path made
//! the plain march 4x slower), so each ray setup, compositing family, gradient source, light and volume layout
//! gets its own SPIR-V (shaders/march.glsl). This file is the one list of them: build.rs compiles every
//! [`MarchKey::all`] (it includes this file by `#[path]`, so it uses nothing of the crate) into a table in
//! [`MarchKey::index`] order, and the renderer computes a frame's key and indexes that table by it.

/// How the march finds its ray: the shader file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setup {
    /// Entry and exit positions from rasterised faces (pass 3 of the entry/exit method).
    Faces,
    /// The slab box intersected per pixel, in a fullscreen fragment pass.
    Analytic,
    /// The same as a compute pass.
    Compute,
}

impl Setup {
    pub const ALL: [Setup; 3] = [Setup::Faces, Setup::Analytic, Setup::Compute];

    pub fn file(self) -> &'static str {
        match self {
            Setup::Faces => "march_faces.frag",
            Setup::Analytic => "march_analytic.frag",
            Setup::Compute => "march_compute.comp",
        }
    }
}

/// Where a shaded family takes its gradients and light from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lighting {
    /// From the precomputed gradient texture instead of six samples per gradient.
    pub gradient_texture: bool,
    /// Shadows or occlusion from rule 9's light grid.
    pub light_volume: bool,
}

impl Lighting {
    pub const ALL: [Lighting; 4] = [
        Lighting::new(false, false),
        Lighting::new(true, false),
        Lighting::new(false, true),
        Lighting::new(true, true),
    ];

    pub const fn new(gradient_texture: bool, light_volume: bool) -> Lighting {
        Lighting {
            gradient_texture,
            light_volume,
        }
    }

    fn defines(self) -> impl Iterator<Item = &'static str> {
        let texture = self.gradient_texture.then_some("GRADIENT_TEXTURE");
        texture.into_iter().chain(self.light_volume.then_some("LIGHT_VOLUME"))
    }

    fn suffix(self) -> String {
        let texture = if self.gradient_texture { "_tex" } else { "" };
        let light = if self.light_volume { "_lv" } else { "" };
        format!("{texture}{light}")
    }
}

/// What the march does with its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Emission-absorption or the density model, without gradients.
    Emission,
    /// The same with gradients: shading or gradient-modulated opacity.
    EmissionShaded(Lighting),
    /// MIP, MinIP or average.
    Projection,
    /// Iso-surfaces (always shaded).
    Isosurface(Lighting),
    /// Emission or density with layers of these kinds mixed in at each sample (rule 13): unshaded (None) or
    /// shaded with gradients of six samples or the gradient texture (no light grid).
    Layers(LayerKinds, Option<Lighting>),
}

/// The kinds of layer a layered frame mixes: its march has a loop for each kind it holds, and none for the other
/// (lavapipe runs a loop's body at least once, even when no layer of its kind is held); and the code of rule 13's
/// other blends only where an overlay takes one (lavapipe runs both sides of a branch).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKinds {
    Overlays,
    Labels,
    Both,
    /// Overlays, one at least blended by maximum or addition.
    OverlaysBlended,
    /// Both kinds, an overlay at least blended by maximum or addition.
    BothBlended,
}

impl LayerKinds {
    pub const ALL: [LayerKinds; 5] = [
        LayerKinds::Overlays,
        LayerKinds::Labels,
        LayerKinds::Both,
        LayerKinds::OverlaysBlended,
        LayerKinds::BothBlended,
    ];

    /// The kinds of `overlays` overlays and `labels` label maps (at least one of either), `blended` where an
    /// overlay takes a blend other than compositing.
    pub fn of(overlays: usize, labels: usize, blended: bool) -> LayerKinds {
        match (overlays > 0, labels > 0, blended) {
            (true, false, false) => LayerKinds::Overlays,
            (true, false, true) => LayerKinds::OverlaysBlended,
            (false, true, _) => LayerKinds::Labels,
            (_, _, false) => LayerKinds::Both,
            (_, _, true) => LayerKinds::BothBlended,
        }
    }

    fn defines(self) -> &'static [&'static str] {
        match self {
            LayerKinds::Overlays => &["LAYER_OVERLAYS"],
            LayerKinds::Labels => &["LAYER_LABELS"],
            LayerKinds::Both => &["LAYER_OVERLAYS", "LAYER_LABELS"],
            LayerKinds::OverlaysBlended => &["LAYER_OVERLAYS", "LAYER_BLENDS"],
            LayerKinds::BothBlended => &["LAYER_OVERLAYS", "LAYER_LABELS", "LAYER_BLENDS"],
        }
    }

    fn suffix(self) -> &'static str {
        match self {
            LayerKinds::Overlays => "o",
            LayerKinds::Labels => "l",
            LayerKinds::Both => "ol",
            LayerKinds::OverlaysBlended => "ob",
            LayerKinds::BothBlended => "olb",
        }
    }
}

impl Family {
    pub const ALL: [Family; 25] = [
        Family::Emission,
        Family::EmissionShaded(Lighting::ALL[0]),
        Family::EmissionShaded(Lighting::ALL[1]),
        Family::EmissionShaded(Lighting::ALL[2]),
        Family::EmissionShaded(Lighting::ALL[3]),
        Family::Projection,
        Family::Isosurface(Lighting::ALL[0]),
        Family::Isosurface(Lighting::ALL[1]),
        Family::Isosurface(Lighting::ALL[2]),
        Family::Isosurface(Lighting::ALL[3]),
        Family::Layers(LayerKinds::ALL[0], None),
        Family::Layers(LayerKinds::ALL[0], Some(Lighting::ALL[0])),
        Family::Layers(LayerKinds::ALL[0], Some(Lighting::ALL[1])),
        Family::Layers(LayerKinds::ALL[1], None),
        Family::Layers(LayerKinds::ALL[1], Some(Lighting::ALL[0])),
        Family::Layers(LayerKinds::ALL[1], Some(Lighting::ALL[1])),
        Family::Layers(LayerKinds::ALL[2], None),
        Family::Layers(LayerKinds::ALL[2], Some(Lighting::ALL[0])),
        Family::Layers(LayerKinds::ALL[2], Some(Lighting::ALL[1])),
        Family::Layers(LayerKinds::ALL[3], None),
        Family::Layers(LayerKinds::ALL[3], Some(Lighting::ALL[0])),
        Family::Layers(LayerKinds::ALL[3], Some(Lighting::ALL[1])),
        Family::Layers(LayerKinds::ALL[4], None),
        Family::Layers(LayerKinds::ALL[4], Some(Lighting::ALL[0])),
        Family::Layers(LayerKinds::ALL[4], Some(Lighting::ALL[1])),
    ];

    /// Where its gradients and light come from (None: it takes no gradients).
    pub fn lighting(self) -> Option<Lighting> {
        match self {
            Family::EmissionShaded(l) | Family::Isosurface(l) => Some(l),
            Family::Layers(_, l) => l,
            Family::Emission | Family::Projection => None,
        }
    }

    fn defines(self) -> Vec<&'static str> {
        let family = match self {
            Family::Emission => vec!["FAMILY_EMISSION"],
            Family::EmissionShaded(_) => vec!["FAMILY_EMISSION", "SHADED"],
            Family::Projection => vec!["FAMILY_PROJECTION"],
            Family::Isosurface(_) => vec!["FAMILY_ISOSURFACE"],
            Family::Layers(kinds, None) => [&["FAMILY_EMISSION", "LAYERS"][..], kinds.defines()].concat(),
            Family::Layers(kinds, Some(_)) => [&["FAMILY_EMISSION", "SHADED", "LAYERS"][..], kinds.defines()].concat(),
        };
        family
            .into_iter()
            .chain(self.lighting().into_iter().flat_map(Lighting::defines))
            .collect()
    }

    fn suffix(self) -> String {
        let family = match self {
            Family::Emission => "ea".to_string(),
            Family::EmissionShaded(_) => "ea_shaded".to_string(),
            Family::Projection => "proj".to_string(),
            Family::Isosurface(_) => "iso".to_string(),
            Family::Layers(kinds, None) => format!("layers_{}", kinds.suffix()),
            Family::Layers(kinds, Some(_)) => format!("layers_{}_shaded", kinds.suffix()),
        };
        format!("{family}{}", self.lighting().map_or(String::new(), Lighting::suffix))
    }
}

/// How the shaders read the volume (`render::VolumeLayout`): a 3D texture, or the corner texture of 8- or 16-bit
/// data; each either as one brick (no page table: `brick_at` is a constant) or as a pool of bricks behind the page
/// table (`POOL_BRICKS`). Rule 9's light grid pass (light.comp) is compiled once per sampling too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    Texture,
    Corners8,
    Corners16,
    TextureBricks,
    Corners8Bricks,
    Corners16Bricks,
}

impl Sampling {
    pub const ALL: [Sampling; 6] = [
        Sampling::Texture,
        Sampling::Corners8,
        Sampling::Corners16,
        Sampling::TextureBricks,
        Sampling::Corners8Bricks,
        Sampling::Corners16Bricks,
    ];

    pub fn index(self) -> usize {
        position(&Sampling::ALL, self)
    }

    /// The same layout read through the page table.
    pub fn bricked(self) -> Sampling {
        match self {
            Sampling::Texture | Sampling::TextureBricks => Sampling::TextureBricks,
            Sampling::Corners8 | Sampling::Corners8Bricks => Sampling::Corners8Bricks,
            Sampling::Corners16 | Sampling::Corners16Bricks => Sampling::Corners16Bricks,
        }
    }

    pub fn defines(self) -> &'static [&'static str] {
        match self {
            Sampling::Texture => &[],
            Sampling::Corners8 => &["CORNERS8"],
            Sampling::Corners16 => &["CORNERS16"],
            Sampling::TextureBricks => &["POOL_BRICKS"],
            Sampling::Corners8Bricks => &["CORNERS8", "POOL_BRICKS"],
            Sampling::Corners16Bricks => &["CORNERS16", "POOL_BRICKS"],
        }
    }

    /// What the SPIR-V names of this sampling end in.
    pub fn suffix(self) -> &'static str {
        match self {
            Sampling::Texture => "",
            Sampling::Corners8 => "_c8",
            Sampling::Corners16 => "_c16",
            Sampling::TextureBricks => "_b",
            Sampling::Corners8Bricks => "_c8_b",
            Sampling::Corners16Bricks => "_c16_b",
        }
    }
}

/// One compiled march shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MarchKey {
    pub setup: Setup,
    pub family: Family,
    pub sampling: Sampling,
}

impl MarchKey {
    /// How many there are: the length of the table build.rs writes.
    pub const COUNT: usize = Setup::ALL.len() * Family::ALL.len() * Sampling::ALL.len();

    /// Every key, in [`index`](Self::index) order.
    pub fn all() -> impl Iterator<Item = MarchKey> {
        Setup::ALL.into_iter().flat_map(|setup| {
            Family::ALL.into_iter().flat_map(move |family| {
                Sampling::ALL.into_iter().map(move |sampling| MarchKey {
                    setup,
                    family,
                    sampling,
                })
            })
        })
    }

    /// Its place in [`all`](Self::all) and in the table.
    pub fn index(self) -> usize {
        let family = position(&Family::ALL, self.family);
        (position(&Setup::ALL, self.setup) * Family::ALL.len() + family) * Sampling::ALL.len() + self.sampling.index()
    }

    /// The `#define`s build.rs compiles its shader file with.
    pub fn defines(self) -> Vec<&'static str> {
        let mut defines = self.family.defines();
        defines.extend(self.sampling.defines());
        defines
    }

    /// Its SPIR-V's name: the file, the family and lighting, the sampling (`march_faces.frag.iso_tex_c8`).
    pub fn name(self) -> String {
        format!(
            "{}.{}{}",
            self.setup.file(),
            self.family.suffix(),
            self.sampling.suffix()
        )
    }
}

/// Where `value` is in `all`.
fn position<T: PartialEq + Copy>(all: &[T], value: T) -> usize {
    all.iter()
        .position(|&a| a == value)
        .expect("every value of a key's parts is in its ALL")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_listed_once_at_its_index() {
        let keys: Vec<MarchKey> = MarchKey::all().collect();
        assert_eq!(keys.len(), MarchKey::COUNT);
        for (i, key) in keys.iter().enumerate() {
            assert_eq!(key.index(), i, "{key:?}");
        }
        let mut names: Vec<String> = keys.iter().map(|k| k.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), MarchKey::COUNT, "SPIR-V names are unique");
    }

    #[test]
    fn defines_name_one_family_each() {
        for key in MarchKey::all() {
            let defines = key.defines();
            let families = defines.iter().filter(|d| d.starts_with("FAMILY_")).count();
            assert_eq!(families, 1, "{key:?}: {defines:?}");
        }
        let key = MarchKey {
            setup: Setup::Compute,
            family: Family::Isosurface(Lighting::new(true, true)),
            sampling: Sampling::Corners16,
        };
        assert_eq!(
            key.defines(),
            ["FAMILY_ISOSURFACE", "GRADIENT_TEXTURE", "LIGHT_VOLUME", "CORNERS16"]
        );
        assert_eq!(key.name(), "march_compute.comp.iso_tex_lv_c16");
    }
}
