//! Movies: a turntable around the volume or a camera path through keyframes, rendered frame by frame to numbered
//! PNGs and an animated GIF (`volcast render --turntable N` / `--keyframes A.json B.json … --frames N`).
//!
//! - [`path`]: the pure rules for each frame's settings (turntable angles, keyframe interpolation; documented
//!   there);
//! - [`gif`]: [`GifWriter`], frames streamed to a looping GIF (also for the viewer's recorder);
//! - [`keyframes`]: reading the view states and checking they make one movie;
//! - [`progress`]: the progress bar;
//! - here: the outputs' names and the render loop.

pub mod gif;
pub mod keyframes;
pub mod path;
pub mod progress;

pub use gif::GifWriter;
pub use keyframes::read_keyframes;
pub use progress::Progress;

use crate::gpu::{Gpu, GpuError};
use crate::render::headless::Headless;
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;
use std::path::{Path, PathBuf};

/// The most frames one movie may have (a minute at 60 fps, two and a half at the default 25).
pub const MAX_FRAMES: u32 = 3600;

#[derive(Debug, thiserror::Error)]
pub enum MovieError {
    /// A bad option value or combination (the command line's usage errors).
    #[error("{0}")]
    Usage(String),
    /// A keyframe file missing, unreadable or not matching the others.
    #[error("{0}")]
    Input(String),
    /// An output that could not be written.
    #[error("{0}")]
    Write(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The caller's progress callback asked to stop (Python's KeyboardInterrupt); the frames written are removed.
    #[error("stopped after {0} frame(s)")]
    Stopped(u32),
}

/// Checks a movie's frame count, `option` naming where it came from; `min` is 1 for a turntable and 2 for a path
/// (its first and last frames are its first and last states).
pub fn check_frames(n: u32, min: u32, option: &str) -> Result<(), MovieError> {
    if !(min..=MAX_FRAMES).contains(&n) {
        return Err(MovieError::Usage(format!(
            "{option} {n}: a movie has {min} to {MAX_FRAMES} frames"
        )));
    }
    Ok(())
}

/// What a movie's frames are.
#[derive(Clone)]
pub enum Plan {
    /// `frames` frames turning `base` once around the vertical axis ([`path::turntable_frame`]).
    Turntable { base: Box<RenderSettings>, frames: u32 },
    /// `frames` frames along the path through `keys` ([`path::keyframe_frame`]).
    Keyframes { keys: Vec<RenderSettings>, frames: u32 },
}

impl Plan {
    pub fn frame_count(&self) -> u32 {
        match self {
            Plan::Turntable { frames, .. } | Plan::Keyframes { frames, .. } => *frames,
        }
    }

    /// The same movie with rule 13's layers styled `styles` in every frame (the renderer holds them).
    pub fn with_layers(mut self, styles: &[crate::scene::layers::LayerStyle]) -> Plan {
        match &mut self {
            Plan::Turntable { base, .. } => base.layers = styles.to_vec(),
            Plan::Keyframes { keys, .. } => keys.iter_mut().for_each(|k| k.layers = styles.to_vec()),
        }
        self
    }

    /// The first frame's settings.
    pub fn first(&self) -> &RenderSettings {
        match self {
            Plan::Turntable { base, .. } => base,
            Plan::Keyframes { keys, .. } => &keys[0],
        }
    }

    /// The settings of frame `k`.
    pub fn frame(&self, k: u32) -> RenderSettings {
        match self {
            Plan::Turntable { base, frames } => path::turntable_frame(base, k, *frames),
            Plan::Keyframes { keys, frames } => path::keyframe_frame(keys, k, *frames),
        }
    }

    /// The image size every frame has.
    pub fn size(&self) -> (u32, u32) {
        let s = match self {
            Plan::Turntable { base, .. } => base,
            Plan::Keyframes { keys, .. } => match keys.first() {
                Some(s) => s,
                None => return (0, 0),
            },
        };
        (s.width, s.height)
    }
}

/// The files a movie written as `NAME.png` makes: `NAME-0000.png` … (zero-padded to at least four digits, enough
/// for the count) and `NAME.gif`, beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct MovieFiles {
    pub frames: Vec<PathBuf>,
    pub gif: PathBuf,
}

impl MovieFiles {
    pub fn new(output: &Path, count: u32) -> Result<MovieFiles, MovieError> {
        let is_png = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned());
        let (true, Some(stem)) = (is_png, stem.filter(|s| !s.is_empty())) else {
            return Err(MovieError::Usage(format!(
                "{}: name a movie NAME.png (its frames are written as NAME-0000.png …, the animation as NAME.gif)",
                output.display()
            )));
        };
        let digits = count.saturating_sub(1).max(1).to_string().len().max(4);
        let frames = (0..count)
            .map(|k| output.with_file_name(format!("{stem}-{k:0digits$}.png")))
            .collect();
        Ok(MovieFiles {
            frames,
            gif: output.with_file_name(format!("{stem}.gif")),
        })
    }

    /// The line naming what was written.
    pub fn summary(&self, fps: f32) -> String {
        let n = self.frames.len();
        let (first, last) = match (self.frames.first(), self.frames.last()) {
            (Some(a), Some(b)) => (a.display().to_string(), b.display().to_string()),
            _ => return "wrote no frames".into(),
        };
        let pngs = if n == 1 { first } else { format!("{first} … {last}") };
        format!(
            "wrote {n} frame{} {pngs} and {} ({n} frames at {fps} fps, {:.2} s, looping)",
            if n == 1 { "" } else { "s" },
            self.gif.display(),
            n as f64 / f64::from(fps)
        )
    }
}

/// Renders every frame of `plan` with `volume` (placed on `headless` already: whole, or streamed and refined for
/// each frame's view before it is drawn), writing `files` (the GIF at `fps`); `progress` hears the frames
/// done. On an error nothing of the movie is left: the frames written so far are removed and the GIF never
/// appears.
pub fn record(
    gpu: &Gpu,
    headless: &mut Headless,
    volume: &Volume,
    plan: &Plan,
    files: &MovieFiles,
    fps: f32,
    progress: &mut dyn FnMut(u32) -> bool,
) -> Result<(), MovieError> {
    let n = plan.frame_count();
    if files.frames.len() != n as usize {
        return Err(MovieError::Usage(format!(
            "{} frames named for a movie of {n}",
            files.frames.len()
        )));
    }
    let (width, height) = plan.size();
    let mut gif = GifWriter::create(&files.gif, width, height, fps)?;
    let mut written = 0;
    let result = (|| -> Result<(), MovieError> {
        for (k, png) in (0..n).zip(&files.frames) {
            let s = plan.frame(k);
            headless.renderer.refine(gpu, volume, &s)?;
            if s.lighting.gradient_texture && !headless.renderer.has_gradient_texture() {
                headless.renderer.enable_gradient_texture(gpu, volume)?;
            }
            let frame = headless.render(gpu, &s)?;
            crate::render::save::save(&frame.image, png).map_err(MovieError::Write)?;
            written += 1;
            gif.push(&frame.image)?;
            if !progress(k + 1) && k + 1 < n {
                return Err(MovieError::Stopped(k + 1));
            }
        }
        Ok(())
    })();
    let result = result.and_then(|()| gif.finish().map(|_| ()));
    if result.is_err() {
        for png in &files.frames[..written] {
            let _ = std::fs::remove_file(png);
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_numbered_beside_the_output() {
        let f = MovieFiles::new(Path::new("out/spin.png"), 3).unwrap();
        assert_eq!(f.frames[0], Path::new("out/spin-0000.png"));
        assert_eq!(f.frames[2], Path::new("out/spin-0002.png"));
        assert_eq!(f.gif, Path::new("out/spin.gif"));
        let f = MovieFiles::new(Path::new("a.PNG"), 3600).unwrap();
        assert_eq!(f.frames[3599], Path::new("a-3599.png"));
        // Enough digits for any count (MAX_FRAMES keeps it at four; the rule does not depend on that).
        assert_eq!(
            MovieFiles::new(Path::new("a.png"), 10001).unwrap().frames[10000],
            Path::new("a-10000.png")
        );
        for bad in ["a.gif", "a", ".png", "/dev/null"] {
            let e = MovieFiles::new(Path::new(bad), 2).unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains("NAME.png"), "{e}");
        }
        let s = MovieFiles::new(Path::new("m.png"), 50).unwrap().summary(25.0);
        assert!(
            s.contains("50 frames m-0000.png … m-0049.png and m.gif") && s.contains("2.00 s"),
            "{s}"
        );
    }

    #[test]
    fn frame_counts_are_bounded() {
        assert!(check_frames(1, 1, "--turntable").is_ok());
        assert!(check_frames(MAX_FRAMES, 2, "--frames").is_ok());
        let e = check_frames(0, 1, "--turntable").unwrap_err().to_string();
        assert!(e.contains("--turntable 0") && e.contains("3600"), "{e}");
        assert!(check_frames(1, 2, "--frames").is_err());
        assert!(check_frames(MAX_FRAMES + 1, 1, "--turntable").is_err());
    }
}
