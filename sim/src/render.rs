//! Pictures of the world: ASCII for terminals, RGB frames and PNG files.
//!
//! Both show every block in its colour, mark the held block, and draw the goal as a small
//! stack in the top-right corner, as the paper's screen does.

use std::fmt::Write as _;
use std::path::Path;

use image::{Rgb, RgbImage};

use crate::error::Result;
use crate::files::{self, write_error};
use crate::observation::Observation;
use crate::state::{BlockId, MAX_BLOCKS};

/// Side of a cell in pixels in [`Observation::rgb`] frames.
pub const CELL_PIXELS: u32 = 48;

/// Block colours, by block id: red, green and blue first, as in the paper's screen.
pub const PALETTE: [[u8; 3]; MAX_BLOCKS] = [
    [220, 50, 47],
    [40, 160, 60],
    [38, 110, 210],
    [240, 150, 30],
    [140, 80, 190],
    [20, 170, 180],
    [210, 60, 150],
    [140, 90, 50],
    [128, 128, 0],
    [30, 40, 120],
    [250, 150, 180],
    [0, 110, 110],
    [160, 210, 60],
    [120, 20, 40],
    [110, 110, 110],
    [200, 170, 20],
];

/// The colour of `block`.
pub fn colour(block: BlockId) -> [u8; 3] {
    PALETTE[block.index() % MAX_BLOCKS]
}

/// The one-character label of `block`: `0`-`9`, then `a`-`f`.
pub fn label(block: BlockId) -> char {
    char::from_digit(block.0 as u32, 16).unwrap_or('?')
}

/// Whether to colour ASCII output with ANSI escapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colour {
    /// Plain text.
    Never,
    /// 24-bit ANSI colours.
    Always,
}

impl Colour {
    /// Colour when standard output is a terminal and `NO_COLOR` is unset.
    pub fn for_stdout() -> Colour {
        use std::io::IsTerminal;
        if std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none() {
            Colour::Always
        } else {
            Colour::Never
        }
    }
}

/// The world as text, top row first: `.` for a free cell, the block's label for a block,
/// the held block in brackets, and the goal stack beside the top rows.
pub fn ascii(obs: &Observation, colour: Colour) -> String {
    let (w, h) = (obs.grid.width(), obs.grid.height());
    let paint = |b: BlockId, text: String| match colour {
        Colour::Never => text,
        Colour::Always => {
            let [r, g, bl] = crate::render::colour(b);
            format!("\x1b[1;38;2;{r};{g};{bl}m{text}\x1b[0m")
        }
    };
    let order = obs.goal.order();
    let mut out = String::new();
    for row in 0..h.max(order.len() + 1) {
        if row < h {
            let y = (h - 1 - row) as u8;
            for x in 0..w as u8 {
                let cell = crate::grid::Cell::new(x, y);
                match obs.state.block_at(cell) {
                    Some(b) if obs.held_block() == Some(b) => out.push_str(&paint(b, format!("[{}]", label(b)))),
                    Some(b) => out.push_str(&paint(b, format!(" {} ", label(b)))),
                    None => out.push_str(" . "),
                }
            }
        } else {
            out.push_str(&" ".repeat(3 * w));
        }
        // The goal column: a header, then the stack top first.
        if row == 0 {
            out.push_str("   goal");
        } else if let Some(&b) = order.len().checked_sub(row).and_then(|i| order.get(i)) {
            out.push_str("    ");
            out.push_str(&paint(b, label(b).to_string()));
        }
        let trimmed = out.trim_end_matches(' ').len();
        out.truncate(trimmed);
        out.push('\n');
    }
    match obs.held_block() {
        Some(b) => writeln!(out, "held: {}", label(b)),
        None => writeln!(out, "held: none"),
    }
    .expect("writing to a String cannot fail");
    out
}

/// The world as an RGB image, `cell` pixels per cell, with the goal stack in a margin at
/// the top-right corner.
pub fn frame(obs: &Observation, cell: u32) -> RgbImage {
    let (w, h) = (obs.grid.width() as u32, obs.grid.height() as u32);
    let n = obs.goal.block_count() as u32;
    let mini = (cell / 3).max(3);
    let margin = 2 * mini;
    let pad = mini / 2;
    let width = w * cell + margin + 2 * pad;
    let height = (h * cell).max(n * mini + 2 * pad);
    let mut img = RgbImage::from_pixel(width, height, Rgb([250, 250, 250]));
    // Grid lines.
    for i in 0..=w {
        fill(&mut img, (i * cell).min(w * cell - 1), 0, 1, h * cell, [215, 215, 215]);
    }
    for j in 0..=h {
        fill(&mut img, 0, (j * cell).min(h * cell - 1), w * cell, 1, [215, 215, 215]);
    }
    let border = (cell / 16).max(1);
    for (i, &c) in obs.blocks().iter().enumerate() {
        let b = BlockId(i as u8);
        // Image rows grow downward, grid rows upward.
        let (px, py) = (u32::from(c.x) * cell, (h - 1 - u32::from(c.y)) * cell);
        fill(
            &mut img,
            px + border,
            py + border,
            cell - 2 * border,
            cell - 2 * border,
            [40, 40, 40],
        );
        fill(
            &mut img,
            px + 2 * border,
            py + 2 * border,
            cell - 4 * border,
            cell - 4 * border,
            colour(b),
        );
        if obs.held_block() == Some(b) {
            // The held block carries a white square with a dark core: a "grip" mark.
            let s = cell / 3;
            fill(&mut img, px + s, py + s, s, s, [255, 255, 255]);
            fill(
                &mut img,
                px + s + s / 3,
                py + s + s / 3,
                s - 2 * (s / 3),
                s - 2 * (s / 3),
                [30, 30, 30],
            );
        }
    }
    // The goal stack, top block first, in the top-right margin.
    let gx = w * cell + pad + (margin - mini) / 2;
    for (k, &b) in obs.goal.order().iter().rev().enumerate() {
        let gy = pad + k as u32 * mini;
        fill(&mut img, gx, gy, mini, mini, [40, 40, 40]);
        fill(&mut img, gx + 1, gy + 1, mini - 2, mini - 2, colour(b));
    }
    img
}

/// Writes [`frame`] of `obs` to `path` as a PNG, atomically.
pub fn save_png(obs: &Observation, path: &Path, cell: u32) -> Result<()> {
    let mut bytes = Vec::new();
    frame(obs, cell)
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| write_error(path, &e))?;
    files::write_atomic(path, &bytes)
}

fn fill(img: &mut RgbImage, x: u32, y: u32, w: u32, h: u32, rgb: [u8; 3]) {
    for yy in y..(y + h).min(img.height()) {
        for xx in x..(x + w).min(img.width()) {
            img.put_pixel(xx, yy, Rgb(rgb));
        }
    }
}
