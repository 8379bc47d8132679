//! A tiny 5×7 bitmap font for the colour bar's labels: digits, the characters numbers are written with
//! (`-`, `+`, `.`, `e`) and the few letters units need. Each glyph is seven rows, top first; bit 4 of a row is
//! its leftmost pixel.

pub const GLYPH_WIDTH: u32 = 5;
pub const GLYPH_HEIGHT: u32 = 7;
/// Advance from one character to the next (one pixel of space).
pub const ADVANCE: u32 = GLYPH_WIDTH + 1;

const GLYPHS: &[(char, [u8; 7])] = &[
    ('0', [0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110]),
    ('1', [0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110]),
    ('2', [0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111]),
    ('3', [0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110]),
    ('4', [0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010]),
    ('5', [0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110]),
    ('6', [0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110]),
    ('7', [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000]),
    ('8', [0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110]),
    ('9', [0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100]),
    ('-', [0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000]),
    ('+', [0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000]),
    ('.', [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100]),
    ('e', [0b00000, 0b00000, 0b01110, 0b10001, 0b11111, 0b10000, 0b01110]),
    ('a', [0b00000, 0b00000, 0b01110, 0b00001, 0b01111, 0b10001, 0b01111]),
    ('x', [0b00000, 0b00000, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001]),
    // The scale bar's units (render/scale_bar.rs): mm and µm.
    ('m', [0b00000, 0b00000, 0b11010, 0b10101, 0b10101, 0b10101, 0b10101]),
    ('µ', [0b00000, 0b00000, 0b10001, 0b10001, 0b10011, 0b11101, 0b10000]),
    ('H', [0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001]),
    ('U', [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110]),
    ('M', [0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001]),
    ('R', [0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001]),
    ('T', [0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100]),
    (' ', [0; 7]),
];

/// The glyph of `c`; characters the font lacks are drawn as a hollow box, so a missing glyph shows.
pub fn glyph(c: char) -> [u8; 7] {
    GLYPHS
        .iter()
        .find(|(g, _)| *g == c)
        .map(|(_, rows)| *rows)
        .unwrap_or([0b11111, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b11111])
}

/// Width in pixels of `text` at `scale` (no trailing space).
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    (n * ADVANCE).saturating_sub(1) * scale
}

/// Calls `set(x, y)` for every lit pixel of `text` with its top-left corner at (x0, y0), each font pixel a
/// `scale`×`scale` square.
pub fn for_each_pixel(text: &str, x0: i64, y0: i64, scale: u32, mut set: impl FnMut(i64, i64)) {
    let s = i64::from(scale.max(1));
    for (k, c) in text.chars().enumerate() {
        let left = x0 + k as i64 * i64::from(ADVANCE) * s;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH_WIDTH {
                if bits & (1 << (GLYPH_WIDTH - 1 - col)) != 0 {
                    for dy in 0..s {
                        for dx in 0..s {
                            set(left + i64::from(col) * s + dx, y0 + row as i64 * s + dy);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_fits_five_columns_and_digits_differ() {
        for (c, rows) in GLYPHS {
            assert!(rows.iter().all(|r| *r < 32), "{c}");
        }
        let digits: Vec<[u8; 7]> = ('0'..='9').map(glyph).collect();
        for i in 0..10 {
            for j in i + 1..10 {
                assert_ne!(digits[i], digits[j], "{i} and {j}");
            }
        }
        assert_eq!(glyph('?'), glyph('~'), "unknown characters share the box");
    }

    #[test]
    fn pixels_land_where_the_glyph_says() {
        let mut lit = Vec::new();
        for_each_pixel("-", 10, 20, 2, |x, y| lit.push((x, y)));
        // '-' is row 3, all five columns: 10 by 2 pixels at scale 2.
        assert_eq!(lit.len(), 20);
        assert!(lit.iter().all(|&(x, y)| (10..20).contains(&x) && (26..28).contains(&y)));
        assert_eq!(text_width("12", 1), 11);
        assert_eq!(text_width("", 3), 0);
    }
}
