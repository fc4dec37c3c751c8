//! The on-screen text of the window: the readout (frame rate, per-pass times, VPLs, grid
//! lights, settings) and the help, drawn over the presented pixels with the 8x8 bitmap font
//! of the `font8x8` crate. Only the window's copy is drawn on: rendered frames, screenshots
//! and statistics never carry the text.

use font8x8::{BASIC_FONTS, UnicodeFonts};
use lgh_render::methods::lgh::INTERACTIVE_INTERLEAVE;

use crate::engine::ShownFrame;
use crate::state::{ViewState, control_lines};

/// Pixels of a glyph (the font's 8), times the text scale.
const CELL: usize = 8;
/// Pixels from one line of text to the next, times the text scale.
const LINE: usize = 10;
/// Timings that sum others, left out of the readout's passes.
const SUMS: [&str; 3] = ["total", "frame", "indirect"];
/// Passes listed in the readout, slowest first.
const PASSES_SHOWN: usize = 8;

/// The readout of a shown frame: rate and frame time, method and settings, lights, the
/// slowest passes in ms.
#[must_use]
pub fn readout(f: &ShownFrame, s: &ViewState) -> Vec<String> {
    let st = &s.settings;
    let mut lines = vec![
        format!("{:.1} fps  {:.0} ms", 1e3 / f.ms.max(1e-3), f.ms),
        format!(
            "{} ({})  alpha {}  interleave {}  k {}",
            st.method.name(),
            f.device,
            st.lgh.alpha,
            st.tiling.interleave.unwrap_or(INTERACTIVE_INTERLEAVE),
            st.shadow_samples(),
        ),
        match f.grid_lights {
            Some(g) => format!("{} VPLs  {g} grid lights", f.vpls),
            None => format!("{} VPLs", f.vpls),
        },
    ];
    if let Some(l) = st.lgh.only_level {
        lines.push(format!("grid level {l} alone (G: next)"));
    }
    if let Some((mean, max)) = f.overdraw {
        lines.push(format!("heat map: {mean:.0} lights per pixel, top {max}"));
    }
    if f.accumulated > 1 {
        lines.push(format!("{} frames accumulated", f.accumulated));
    }
    let mut passes: Vec<&(String, f64)> = f
        .timings
        .iter()
        .filter(|(n, _)| !SUMS.contains(&n.as_str()))
        .collect();
    passes.sort_by(|a, b| b.1.total_cmp(&a.1));
    lines.extend(
        passes
            .iter()
            .take(PASSES_SHOWN)
            .map(|(n, ms)| format!("{ms:6.1} ms  {n}")),
    );
    lines.push("H: help".to_string());
    lines
}

/// The help: one line per control.
#[must_use]
pub fn help() -> Vec<String> {
    let mut lines = vec!["lgh view controls".to_string()];
    lines.extend(control_lines());
    lines
}

/// Draws `lines` at pixel (`x0`, `y0`) of the `w` x `h` buffer `buf` (one `0x00RRGGBB` per
/// pixel), `scale` screen pixels per font pixel, white on a darkened box; clipped at the
/// buffer's edges (text outside draws nothing). Characters the font lacks draw as blanks.
/// Returns the row just below the box.
pub fn draw(
    buf: &mut [u32],
    w: usize,
    h: usize,
    (x0, y0): (usize, usize),
    lines: &[String],
    scale: usize,
) -> usize {
    let scale = scale.max(1);
    let cell = CELL * scale;
    let step = LINE * scale;
    let below = y0 + lines.len() * step + cell;
    if buf.len() < w * h {
        return below;
    }
    let cols = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    // The box: a margin of half a cell around the text, its pixels at a quarter brightness.
    let pad = cell / 2;
    let (bx1, by1) = ((x0 + cols * cell + 2 * pad).min(w), below.min(h));
    for y in y0.min(h)..by1 {
        for p in &mut buf[y * w + x0.min(w)..y * w + bx1] {
            *p = (*p >> 2) & 0x003f_3f3f;
        }
    }
    for (row, line) in lines.iter().enumerate() {
        for (col, ch) in line.chars().enumerate() {
            let Some(glyph) = BASIC_FONTS.get(ch) else {
                continue;
            };
            let (gx, gy) = (x0 + pad + col * cell, y0 + pad + row * step);
            for (fy, bits) in glyph.iter().enumerate() {
                for fx in 0..CELL {
                    if bits & (1 << fx) == 0 {
                        continue;
                    }
                    for sy in 0..scale {
                        let y = gy + fy * scale + sy;
                        if y >= h {
                            break;
                        }
                        for sx in 0..scale {
                            let x = gx + fx * scale + sx;
                            if x < w {
                                buf[y * w + x] = 0x00ff_ffff;
                            }
                        }
                    }
                }
            }
        }
    }
    below
}

/// The text scale for a window `height` pixels high: 1 up to 480 lines, then 2.
#[must_use]
pub fn scale_for(height: usize) -> usize {
    if height > 480 { 2 } else { 1 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every lit font pixel of a glyph is white in the buffer, at every scale, and every
    /// pixel of the box that is not a glyph pixel is darkened, not whitened.
    #[test]
    fn glyphs_land_where_the_font_says() {
        for scale in [1, 2, 3] {
            let (w, h) = (64, 40);
            let mut buf = vec![0x0080_8080u32; w * h];
            let below = draw(&mut buf, w, h, (3, 5), &["Ag".to_string()], scale);
            assert_eq!(below, 5 + (LINE + CELL) * scale);
            let pad = CELL * scale / 2;
            for (col, ch) in ['A', 'g'].into_iter().enumerate() {
                let glyph = BASIC_FONTS.get(ch).unwrap_or_default();
                for y in 0..CELL * scale {
                    for x in 0..CELL * scale {
                        let (px, py) = (3 + pad + col * CELL * scale + x, 5 + pad + y);
                        if px >= w || py >= h {
                            continue;
                        }
                        let lit = glyph[y / scale] & (1 << (x / scale)) != 0;
                        let want = if lit { 0x00ff_ffff } else { 0x0020_2020 };
                        assert_eq!(buf[py * w + px], want, "scale {scale} {ch} ({x}, {y})");
                    }
                }
            }
            // Outside the box nothing changed.
            assert_eq!(buf[0], 0x0080_8080);
        }
    }

    /// Text larger than the buffer, or placed outside it, is clipped without a panic; a
    /// buffer shorter than w x h is left alone.
    #[test]
    fn drawing_is_clipped() {
        let lines = help();
        for (w, h, x0, y0) in [
            (10, 7, 0, 0),
            (1, 1, 0, 0),
            (50, 50, 49, 49),
            (50, 50, 500, 500),
        ] {
            let mut buf = vec![0u32; w * h];
            draw(&mut buf, w, h, (x0, y0), &lines, 2);
        }
        let mut short = vec![7u32; 3];
        draw(&mut short, 10, 10, (0, 0), &lines, 1);
        assert_eq!(short, vec![7; 3]);
    }
}
