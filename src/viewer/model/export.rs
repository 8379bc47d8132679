//! The "Export figure" section's state: the size typed for a figure rendered offscreen from the session (any size
//! up to the device's limit, unlike F12's view-sized screenshot), whether it carries the colour bar and the scale bar, and what
//! became of the last one.

/// What the export fields hold, as typed.
#[derive(Clone, Debug)]
pub struct FigureExport {
    pub width: String,
    pub height: String,
    pub colorbar: bool,
    /// A scale bar at the bottom left (`render/scale_bar.rs`): on unless switched off.
    pub scale_bar: bool,
    /// The last export: the file written, or why not.
    pub last: Option<Result<String, String>>,
}

impl Default for FigureExport {
    fn default() -> FigureExport {
        FigureExport {
            width: "1920".into(),
            height: "1080".into(),
            colorbar: true,
            scale_bar: true,
            last: None,
        }
    }
}

impl FigureExport {
    /// The typed size, each side 1..=`limit` pixels, or what is wrong with it.
    pub fn size(&self, limit: u32) -> Result<(u32, u32), String> {
        let side = |text: &str, what: &str| match text.trim().parse::<u32>() {
            Ok(v) if (1..=limit).contains(&v) => Ok(v),
            _ => Err(format!(
                "{what} '{}' is not a whole number from 1 to {limit}",
                text.trim()
            )),
        };
        Ok((side(&self.width, "width")?, side(&self.height, "height")?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked_against_the_limit() {
        let mut e = FigureExport::default();
        assert_eq!(e.size(16384), Ok((1920, 1080)));
        e.width = " 1600 ".into();
        e.height = "1000".into();
        assert_eq!(e.size(16384), Ok((1600, 1000)));
        e.width = "20000".into();
        assert!(e.size(16384).unwrap_err().contains("width '20000'"));
        e.width = "0".into();
        assert!(e.size(16384).is_err());
        e.width = "12x".into();
        assert!(e.size(16384).is_err());
    }
}
