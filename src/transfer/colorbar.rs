//! A colour bar for a classification (a transfer function or the simple colormap model) drawn into an RGBA8
//! image: the colours over the visible value window, top = the window's upper end, at full opacity; to its left a
//! sideways plot of the opacity (bar length ∝ opacity per step, relative to the largest opacity in the window,
//! so faint transfer functions still show their shape); to its right ticks at nice round values in data units
//! with labels in a built-in bitmap font, and the unit ("HU") above. `render --colorbar` appends it as a strip
//! at the right of the image. Pure code.

mod font;

pub use font::{for_each_pixel as for_each_text_pixel, text_width, GLYPH_HEIGHT};

use crate::transfer::function::{bake, linear_to_srgb, lookup, Classification};
use image::{Rgba, RgbaImage};

/// What a colour bar shows.
#[derive(Clone, Debug)]
pub struct ColorbarSpec<'a> {
    pub classification: &'a Classification,
    /// Visible value window, normalised (fractions of `range`).
    pub window: [f32; 2],
    /// The data's value range (data units).
    pub range: [f64; 2],
    /// The values' unit, drawn above the bar ("HU").
    pub unit: Option<&'a str>,
    /// sRGB background of the strip (the render's background, so the strip joins it).
    pub background: [u8; 3],
}

/// Where the parts of a bar of a given height lie (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    pub scale: u32,
    pub width: u32,
    pub height: u32,
    /// The opacity plot's columns.
    pub opacity_x: [u32; 2],
    /// The colour bar's columns.
    pub bar_x: [u32; 2],
    /// The colour bar's rows: `bar_y[0]` is the top (the window's upper value), `bar_y[1]` one past the bottom.
    pub bar_y: [u32; 2],
    /// Where the tick labels start.
    pub label_x: u32,
}

impl Layout {
    /// The window's data values [lo, hi].
    fn data_window(spec: &ColorbarSpec) -> [f64; 2] {
        let [min, max] = spec.range;
        spec.window.map(|w| min + f64::from(w) * (max - min))
    }

    /// The normalised value at the centre of bar row `y`.
    pub fn value_at_row(&self, spec: &ColorbarSpec, y: u32) -> f32 {
        let [lo, hi] = spec.window;
        let rows = (self.bar_y[1] - self.bar_y[0]).max(1) as f32;
        let t = ((y as f32 + 0.5 - self.bar_y[0] as f32) / rows).clamp(0.0, 1.0);
        hi - t * (hi - lo)
    }

    /// The bar row whose centre is nearest the data value `v` (None outside the window).
    pub fn row_of(&self, spec: &ColorbarSpec, v: f64) -> Option<u32> {
        let [lo, hi] = Layout::data_window(spec);
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) || v < lo || v > hi {
            return None;
        }
        let rows = f64::from(self.bar_y[1] - self.bar_y[0]);
        let y = f64::from(self.bar_y[0]) + (hi - v) / (hi - lo) * rows - 0.5;
        Some((y.round().max(0.0) as u32).clamp(self.bar_y[0], self.bar_y[1].saturating_sub(1)))
    }
}

/// Steps of 1, 2 or 5 × 10^k: the tick values `k·step` within [lo, hi], at most about `max_count` of them.
pub fn nice_ticks(lo: f64, hi: f64, max_count: usize) -> (Vec<f64>, f64) {
    if !(lo.is_finite() && hi.is_finite()) || hi < lo {
        return (Vec::new(), 0.0);
    }
    if hi == lo {
        return (vec![lo], 0.0);
    }
    let raw = (hi - lo) / max_count.max(1) as f64;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0 * magnitude);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let ticks = (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            if v == 0.0 {
                0.0 // not −0
            } else {
                v
            }
        })
        .collect();
    (ticks, step)
}

/// A tick value as text: as many decimals as the step needs; exponent form for very large or small values.
pub fn tick_label(v: f64, step: f64) -> String {
    let big = v.abs() >= 1e5 || (step > 0.0 && step < 1e-3);
    if big && v != 0.0 {
        let text = format!("{v:e}");
        // Rounding noise in the mantissa (2.0000000000000004e-5) is cut to the step's precision.
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let m: f64 = mantissa.parse().unwrap_or(0.0);
        return format!("{}e{exponent}", trim(format!("{m:.3}")));
    }
    let decimals = if step > 0.0 {
        (-step.log10().floor()).max(0.0) as usize
    } else {
        3
    };
    trim(format!("{v:.decimals$}"))
}

fn trim(s: String) -> String {
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// The layout of a bar `height` pixels high for `spec`.
pub fn layout(spec: &ColorbarSpec, height: u32) -> Layout {
    let scale = (height / 256).clamp(1, 3);
    let pad = 4 * scale;
    let opacity_x = [pad, pad + 10 * scale];
    let bar_x = [opacity_x[1] + scale, opacity_x[1] + scale + 12 * scale];
    let label_x = bar_x[1] + 5 * scale;
    let top = pad + GLYPH_HEIGHT * scale + pad;
    let bottom = pad + GLYPH_HEIGHT * scale / 2 + 1;
    let bar_y = [top.min(height), height.saturating_sub(bottom).max(top.min(height))];
    let (ticks, step) = ticks_for(spec, bar_y, scale);
    let widest = ticks
        .iter()
        .map(|&t| text_width(&tick_label(t, step), scale))
        .chain(spec.unit.map(|u| text_width(u, scale)))
        .max()
        .unwrap_or(0);
    Layout {
        scale,
        width: label_x + widest.max(3 * font::ADVANCE * scale) + pad,
        height,
        opacity_x,
        bar_x,
        bar_y,
        label_x,
    }
}

/// Ticks at least three label heights apart.
fn ticks_for(spec: &ColorbarSpec, bar_y: [u32; 2], scale: u32) -> (Vec<f64>, f64) {
    let rows = bar_y[1].saturating_sub(bar_y[0]);
    let max_count = (rows / (3 * GLYPH_HEIGHT * scale)).max(1) as usize;
    let [lo, hi] = Layout::data_window(spec);
    nice_ticks(lo, hi, max_count)
}

/// The sRGB colour (8-bit) and opacity per step the classification gives the normalised value `v`, from the
/// same baked table the renderer uses.
pub fn colour_at(lut: &[[f32; 4]], v: f32) -> ([u8; 3], f32) {
    let e = lookup(lut, v);
    let c = |x: f32| (linear_to_srgb(x.clamp(0.0, 1.0)) * 255.0).round() as u8;
    ([c(e[0]), c(e[1]), c(e[2])], e[3])
}

/// The colour bar for `spec`, `height` pixels high (width from the labels: [`Layout::width`]).
pub fn colorbar(spec: &ColorbarSpec, height: u32) -> RgbaImage {
    let l = layout(spec, height);
    let [br, bg, bb] = spec.background;
    let mut img = RgbaImage::from_pixel(l.width, height, Rgba([br, bg, bb, 255]));
    let luma = 0.2126 * f32::from(br) + 0.7152 * f32::from(bg) + 0.0722 * f32::from(bb);
    let ink = if luma > 128.0 {
        Rgba([0, 0, 0, 255])
    } else {
        Rgba([235, 235, 235, 255])
    };
    let faint = if luma > 128.0 {
        Rgba([200, 200, 200, 255])
    } else {
        Rgba([50, 50, 50, 255])
    };
    if l.bar_y[1] <= l.bar_y[0] {
        return img;
    }
    let lut = bake(spec.classification, spec.window, spec.range);
    let rows: Vec<([u8; 3], f32)> = (l.bar_y[0]..l.bar_y[1])
        .map(|y| colour_at(&lut, l.value_at_row(spec, y)))
        .collect();
    let max_alpha = rows.iter().map(|r| r.1).fold(0.0f32, f32::max);
    for (y, (rgb, alpha)) in (l.bar_y[0]..).zip(&rows) {
        for x in l.bar_x[0]..l.bar_x[1] {
            img.put_pixel(x, y, Rgba([rgb[0], rgb[1], rgb[2], 255]));
        }
        let plot = l.opacity_x[1] - l.opacity_x[0];
        let filled = if max_alpha > 0.0 {
            (alpha / max_alpha * plot as f32).round() as u32
        } else {
            0
        };
        for x in l.opacity_x[0]..l.opacity_x[1] {
            // The plot grows leftwards from the bar, so it reads as the opacity at that row of the bar.
            let lit = x >= l.opacity_x[1] - filled.min(plot);
            img.put_pixel(x, y, if lit { ink } else { faint });
        }
    }
    let (ticks, step) = ticks_for(spec, l.bar_y, l.scale);
    let mut text = |s: &str, x: i64, y: i64| {
        font::for_each_pixel(s, x, y, l.scale, |px, py| {
            if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                img.put_pixel(px as u32, py as u32, ink);
            }
        })
    };
    for &t in &ticks {
        if let Some(y) = l.row_of(spec, t) {
            let label = tick_label(t, step);
            text(
                &label,
                i64::from(l.label_x),
                i64::from(y) - i64::from(GLYPH_HEIGHT * l.scale / 2),
            );
        }
    }
    if let Some(unit) = spec.unit {
        text(unit, i64::from(l.label_x), i64::from(4 * l.scale));
    }
    for &t in &ticks {
        if let Some(y) = l.row_of(spec, t) {
            for x in l.bar_x[1]..l.bar_x[1] + 3 * l.scale {
                img.put_pixel(x, y, ink);
            }
        }
    }
    img
}

/// `image` with the colour bar appended at its right: the image grows by the bar's width and keeps its pixels.
pub fn append_colorbar(image: &RgbaImage, spec: &ColorbarSpec) -> RgbaImage {
    let bar = colorbar(spec, image.height());
    let mut out = RgbaImage::new(image.width() + bar.width(), image.height());
    image::imageops::replace(&mut out, image, 0, 0);
    image::imageops::replace(&mut out, &bar, i64::from(image.width()), 0);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::function::{srgb_to_linear, TfUnits, TransferFunction};
    use crate::transfer::Colormap;

    fn ct_tf() -> Classification {
        Classification::Function(TransferFunction {
            name: "t".into(),
            units: TfUnits::Data,
            colors: vec![
                [-1000.0, 0.0, 0.2, 1.0],
                [1000.0, 1.0, 0.8, 0.0],
                [3000.0, 0.5, 0.5, 0.5],
            ],
            colormap: Colormap::Grayscale,
            opacity: vec![[-1000.0, 0.0], [3000.0, 0.5]],
        })
    }

    #[test]
    fn ticks_are_nice_numbers_in_the_window() {
        let (t, step) = nice_ticks(-1024.0, 2986.0, 5);
        assert_eq!(step, 1000.0);
        assert_eq!(t, vec![-1000.0, 0.0, 1000.0, 2000.0]);
        let (t, step) = nice_ticks(0.13, 0.87, 4);
        assert_eq!(step, 0.2);
        assert_eq!(t.len(), 4);
        assert!((t[0] - 0.2).abs() < 1e-12 && (t[3] - 0.8).abs() < 1e-12);
        let (t, _) = nice_ticks(-7.94, 7.94, 8);
        assert_eq!(t, vec![-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0]);
        assert_eq!(nice_ticks(5.0, 5.0, 4).0, vec![5.0]);
        assert!(nice_ticks(f64::NAN, 1.0, 4).0.is_empty());
        assert_eq!(tick_label(-1000.0, 1000.0), "-1000");
        assert_eq!(tick_label(0.2 * 3.0, 0.2), "0.6");
        assert_eq!(tick_label(0.0, 0.25), "0");
        assert_eq!(tick_label(2e-5, 1e-5), "2e-5");
        assert_eq!(tick_label(300000.0, 100000.0), "3e5");
    }

    #[test]
    fn bar_pixels_at_ticks_are_the_transfer_functions_colours() {
        let class = ct_tf();
        let spec = ColorbarSpec {
            classification: &class,
            window: [0.0, 1.0],
            range: [-1024.0, 2986.0],
            unit: Some("HU"),
            background: [0, 0, 0],
        };
        let img = colorbar(&spec, 256);
        let l = layout(&spec, 256);
        assert_eq!(img.width(), l.width);
        let Classification::Function(tf) = &class else {
            unreachable!()
        };
        let points: Vec<(f32, [f32; 3])> = tf.colors.iter().map(|p| (p[0], [p[1], p[2], p[3]])).collect();
        let (ticks, _) = ticks_for(&spec, l.bar_y, l.scale);
        // 236 rows, labels at least 21 rows apart: at most 11 ticks over 4010 HU, so every 500 HU.
        assert_eq!(ticks, (-2..=5).map(|k| f64::from(k) * 500.0).collect::<Vec<_>>());
        for t in ticks {
            let y = l.row_of(&spec, t).unwrap();
            // The definition in sRGB at the tick: a row spans 4010/236 ≈ 17 HU, and the colours change by at most
            // 1/2000 per HU, so the row centre's colour is within ~2.2/255 of the tick's (plus rounding).
            let want = crate::transfer::function::piecewise(&points, t as f32);
            let px = img.get_pixel(l.bar_x[0] + 2, y);
            for c in 0..3 {
                let got = f32::from(px[c]) / 255.0;
                assert!((got - want[c]).abs() <= 3.5 / 255.0, "tick {t}: {px:?} vs {want:?}");
                // The pixel is the sRGB colour, not its linear value.
                assert!((srgb_to_linear(got) - srgb_to_linear(want[c])).abs() < 0.02);
            }
            // A tick mark beside the bar.
            assert_eq!(img.get_pixel(l.bar_x[1], y)[0], 235);
        }
        // Top of the bar is the window's upper end.
        let top = img.get_pixel(l.bar_x[0], l.bar_y[0]);
        assert!((i32::from(top[0]) - 128).abs() <= 2, "{top:?}");
    }

    #[test]
    fn labels_and_unit_are_drawn_and_opacity_plotted() {
        let class = ct_tf();
        let spec = ColorbarSpec {
            classification: &class,
            window: [0.0, 1.0],
            range: [-1024.0, 2986.0],
            unit: Some("HU"),
            background: [0, 0, 0],
        };
        let img = colorbar(&spec, 256);
        let l = layout(&spec, 256);
        let ink_in = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y)[0] == 235)
                .count()
        };
        // "HU" above the labels: H and U have 17 + 15 lit pixels at scale 1.
        assert_eq!(ink_in(l.label_x, l.width, 0, l.bar_y[0]), 32);
        // Each tick's label: some ink in the rows around the tick, none far from any tick.
        for t in [-1000.0, 0.0, 1000.0, 2000.0] {
            let y = l.row_of(&spec, t).unwrap();
            assert!(ink_in(l.label_x, l.width, y - 3, y + 4) >= 8, "label of {t}");
        }
        let y0 = l.row_of(&spec, -1000.0).unwrap();
        let y1 = l.row_of(&spec, -500.0).unwrap();
        let mid = (y0 + y1) / 2;
        assert_eq!(ink_in(l.label_x, l.width, mid - 2, mid + 2), 0, "between labels");
        // Opacity rises with the value: the plot is fuller at the top than at the bottom.
        let top = ink_in(l.opacity_x[0], l.opacity_x[1], l.bar_y[0], l.bar_y[0] + 1);
        let bottom = ink_in(l.opacity_x[0], l.opacity_x[1], l.bar_y[1] - 1, l.bar_y[1]);
        assert_eq!(top, 10, "full width at the largest opacity");
        assert_eq!(bottom, 0);
    }

    #[test]
    fn appended_strip_keeps_the_image_and_tiny_images_do_not_panic() {
        let class = Classification::Simple {
            colormap: Colormap::Viridis,
            step_alpha: 0.1,
            multiplied: false,
        };
        let spec = ColorbarSpec {
            classification: &class,
            window: [0.25, 0.75],
            range: [0.0, 1.0],
            unit: None,
            background: [255, 255, 255],
        };
        let src = RgbaImage::from_pixel(40, 64, Rgba([9, 8, 7, 255]));
        let out = append_colorbar(&src, &spec);
        assert_eq!(out.height(), 64);
        assert!(out.width() > 40);
        assert!((0..40).all(|x| *out.get_pixel(x, 10) == Rgba([9, 8, 7, 255])));
        assert_eq!(*out.get_pixel(out.width() - 1, 0), Rgba([255, 255, 255, 255]));
        for h in [0, 1, 5, 20] {
            let img = colorbar(&spec, h);
            assert_eq!(img.height(), h);
        }
    }
}
