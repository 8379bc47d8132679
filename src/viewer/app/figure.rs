//! "Export figure" carried out: the view state's render at the typed size, the colour bar fitted inside that
//! width and the scale bar drawn on it when asked, saved as `volcast-<date>_<time>.png` with its view state beside it (so `volcast render
//! --state` renders it again); where it went, or why not, shows under the button.

use super::running::Running;
use crate::render::figure::{annotated, colorbar_width};
use crate::viewer::session::write_session;
use std::path::PathBuf;

impl Running {
    pub(super) fn export_figure(&mut self) {
        let result = self.write_figure();
        match &result {
            Ok(path) => eprintln!("exported figure {path}"),
            Err(e) => eprintln!("export figure: {e}"),
        }
        self.model.export.last = Some(result);
    }

    fn write_figure(&mut self) -> Result<String, String> {
        let export = &self.model.export;
        let (width, height) = export.size(self.presenter.max_texture_side() as u32)?;
        let volume = self.shown.for_slices().ok_or("no volume is shown")?;
        // The bar's width depends only on the height: the render takes what is left of the figure's width.
        let probe = self.model.render_settings(width, height);
        let bar = if export.colorbar {
            colorbar_width(&probe, volume, height)
        } else {
            0
        };
        if bar >= width {
            return Err(format!(
                "{width} pixels leave no room beside the colour bar ({bar} pixels)"
            ));
        }
        let s = self.model.render_settings(width - bar, height);
        let image = self
            .presenter
            .render_offscreen(volume, &s, &self.loader.limits().budgets)
            .map_err(|e| e.to_string())?;
        let image = annotated(image, &s, volume, bar > 0, export.scale_bar);
        let path: PathBuf = self.capture.new_name("png");
        crate::render::save::save(&image, &path)?;
        write_session(&path.with_extension("json"), &self.view_state(&s))?;
        Ok(format!("{} ({}x{})", path.display(), image.width(), image.height()))
    }
}
