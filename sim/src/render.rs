//! Pictures of the world: ASCII for terminals, RGB frames, and PNG or JPEG files.
//!
//! Both show every block in its colour, mark the held block, and draw the goal as a small
//! stack in the top-right corner, as the paper's screen does (a goal of several towers as
//! its towers, one under the other, a gap between them). The side view is drawn the same
//! way (`y` is up in both), with the table under the bottom row. A picture file's format is
//! the one its name says ([`PictureFormat::of`]); a picture is at most
//! [`MAX_PICTURE_SIDE`] pixels a side and [`MAX_PICTURE_PIXELS`] in all, so that no cell
//! size asks for gigabytes.

use std::fmt::Write as _;
use std::path::Path;

use files::OutputPath;
use image::{Rgb, RgbImage};

use crate::error::{Result, SimError};
use crate::grid::Grid;
use crate::observation::Observation;
use crate::state::{BlockId, MAX_BLOCKS};
use crate::view::View;

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

/// The one-character label of `block`: `0`-`9`, then `A`-`F` (capitals, so that no label is
/// a lower-case letter a key already means: `blockstack demo` picks a block by its label
/// and drops with `d`).
pub fn label(block: BlockId) -> char {
    char::from_digit(block.0 as u32, 16).map_or('?', |c| c.to_ascii_uppercase())
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
/// the held block in brackets, and the goal stack beside the top rows (a goal of towers:
/// its towers, a blank line between them); in the side view a line of `=` under the bottom
/// row is the table.
pub fn ascii(obs: &Observation, colour: Colour) -> String {
    let (w, h) = (obs.grid.width(), obs.grid.height());
    let paint = |b: BlockId, text: String| match colour {
        Colour::Never => text,
        Colour::Always => {
            let [r, g, bl] = crate::render::colour(b);
            format!("\x1b[1;38;2;{r};{g};{bl}m{text}\x1b[0m")
        }
    };
    // The goal column, top first: each tower top block first, `None` for the gap between.
    let mut order: Vec<Option<BlockId>> = Vec::new();
    for tower in obs.goal.towers().collect::<Vec<_>>().iter().rev() {
        if !order.is_empty() {
            order.push(None);
        }
        order.extend(tower.iter().rev().map(|&b| Some(b)));
    }
    let mut out = String::new();
    for row in 0..h.max(order.len() + 1) {
        if row < h {
            let y = (h - 1 - row) as u16;
            for x in 0..w as u16 {
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
        } else if let Some(&Some(b)) = order.get(row - 1) {
            out.push_str("    ");
            out.push_str(&paint(b, label(b).to_string()));
        }
        let trimmed = out.trim_end_matches(' ').len();
        out.truncate(trimmed);
        out.push('\n');
        if row + 1 == h && obs.view == View::Side {
            out.push_str(&"=".repeat(3 * w));
            out.push('\n');
        }
    }
    match obs.held_block() {
        Some(b) => writeln!(out, "held: {}", label(b)),
        None => writeln!(out, "held: none"),
    }
    .expect("writing to a String cannot fail");
    out
}

/// The largest side of a picture, in pixels.
pub const MAX_PICTURE_SIDE: u64 = 16_384;

/// The most pixels in a picture (2^25: 96 MiB of RGB).
pub const MAX_PICTURE_PIXELS: u64 = 1 << 25;

/// The size in pixels of [`frame`]'s picture of `blocks` blocks on `grid` with `cell`
/// pixels per cell; an error if it is larger than [`MAX_PICTURE_SIDE`] a side or
/// [`MAX_PICTURE_PIXELS`] in all.
pub fn picture_size(grid: Grid, blocks: usize, cell: u32) -> Result<(u32, u32)> {
    let (w, h, n, cell) = (
        grid.width() as u64,
        grid.height() as u64,
        blocks as u64,
        u64::from(cell),
    );
    let mini = (cell / 3).max(3);
    let (margin, pad) = (2 * mini, mini / 2);
    let width = w * cell + margin + 2 * pad;
    let height = (h * cell).max(n * mini + 2 * pad);
    if width > MAX_PICTURE_SIDE || height > MAX_PICTURE_SIDE || width * height > MAX_PICTURE_PIXELS {
        return Err(SimError::PictureTooLarge {
            cell: cell as u32,
            width,
            height,
            max_side: MAX_PICTURE_SIDE,
            max_pixels: MAX_PICTURE_PIXELS,
        });
    }
    Ok((width as u32, height as u32))
}

/// `(width, height)` in pixels of [`frame`]'s picture of a `grid` world with `blocks`
/// blocks, at `cell` pixels a cell: the grid, and beside it the goal in small blocks.
pub fn frame_size(grid: Grid, blocks: usize, cell: u32) -> (u32, u32) {
    let (w, h) = (grid.width() as u32, grid.height() as u32);
    let mini = (cell / 3).max(3);
    let pad = mini / 2;
    (
        w * cell + 2 * mini + 2 * pad,
        (h * cell).max(blocks as u32 * mini + 2 * pad),
    )
}
/// The world as an RGB image, `cell` pixels per cell, with the goal stack in a margin at
/// the top-right corner. Every grid fits the bounds at [`CELL_PIXELS`]; check a cell size
/// given by a person with [`picture_size`] first ([`save_picture`] does).
pub fn frame(obs: &Observation, cell: u32) -> RgbImage {
    let (w, h) = (obs.grid.width() as u32, obs.grid.height() as u32);
    let mini = (cell / 3).max(3);
    let margin = 2 * mini;
    let pad = mini / 2;
    let (width, height) = frame_size(obs.grid, obs.goal.block_count(), cell);
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
        let b = BlockId::of(i);
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
    if obs.view == View::Side {
        // The table: a dark band over the bottom edge of the bottom row.
        fill(
            &mut img,
            0,
            h * cell - border.max(2),
            w * cell,
            border.max(2),
            [110, 80, 50],
        );
    }
    // The goal stack, top block first, in the top-right margin; towers one under the
    // other, the last first, half a block apart.
    let gx = w * cell + pad + (margin - mini) / 2;
    let mut gy = pad;
    for (t, tower) in obs.goal.towers().collect::<Vec<_>>().iter().rev().enumerate() {
        if t > 0 {
            gy += mini / 2;
        }
        for &b in tower.iter().rev() {
            fill(&mut img, gx, gy, mini, mini, [40, 40, 40]);
            fill(&mut img, gx + 1, gy + 1, mini - 2, mini - 2, colour(b));
            gy += mini;
        }
    }
    img
}

/// The file formats a picture is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PictureFormat {
    /// PNG, lossless.
    Png,
    /// JPEG, quality 90.
    Jpeg,
}

impl PictureFormat {
    /// The format `path`'s extension names (`.png`, `.jpg` or `.jpeg`, any case); PNG for
    /// `-` (standard output); an error for any other name.
    pub fn of(path: &Path) -> Result<PictureFormat> {
        if path.as_os_str() == files::STDOUT {
            return Ok(PictureFormat::Png);
        }
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(PictureFormat::Png),
            Some("jpg" | "jpeg") => Ok(PictureFormat::Jpeg),
            _ => Err(SimError::PictureFormat {
                path: path.display().to_string(),
            }),
        }
    }

    /// The bytes of `img` in this format.
    pub fn encode(self, img: &RgbImage) -> std::result::Result<Vec<u8>, image::ImageError> {
        let mut bytes = Vec::new();
        match self {
            PictureFormat::Png => img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?,
            PictureFormat::Jpeg => {
                image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 90).encode_image(img)?
            }
        }
        Ok(bytes)
    }
}

/// Writes [`frame`] of `obs` to `out` in the format its name says ([`PictureFormat::of`]),
/// through the output helper (atomically for a regular file); an error, before drawing,
/// if the picture would be too large ([`picture_size`]).
pub fn save_picture(obs: &Observation, out: &OutputPath, cell: u32) -> Result<()> {
    let format = PictureFormat::of(out.path())?;
    picture_size(obs.grid, obs.goal.block_count(), cell)?;
    let bytes = format.encode(&frame(obs, cell)).map_err(|e| files::FilesError::Write {
        path: out.path().display().to_string(),
        reason: e.to_string(),
        kind: std::io::ErrorKind::InvalidData,
    })?;
    Ok(out.write(&bytes)?)
}

fn fill(img: &mut RgbImage, x: u32, y: u32, w: u32, h: u32, rgb: [u8; 3]) {
    for yy in y..(y + h).min(img.height()) {
        for xx in x..(x + w).min(img.width()) {
            img.put_pixel(xx, yy, Rgb(rgb));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BlockId, Cell, Goal, State};

    fn observation(grid: Grid, blocks: usize) -> Observation {
        let cells: Vec<Cell> = (0..blocks)
            .map(|i| Cell::new((i % grid.width()) as u16, (i / grid.width()) as u16))
            .collect();
        Observation {
            grid,
            state: State::new(&cells, Some(BlockId(0))).unwrap(),
            goal: Goal::from_indices(&(0..blocks).collect::<Vec<_>>()).unwrap(),
            protocol: crate::ActionProtocol::Free,
            view: crate::View::Top,
        }
    }

    #[test]
    fn every_grid_fits_the_picture_bounds_at_the_default_cell_size() {
        for w in 1..=255 {
            for h in (1..=255).filter(|h| w * h <= crate::MAX_CELLS) {
                let grid = Grid::new(w, h).unwrap();
                let blocks = crate::MAX_BLOCKS.min(w * h - 1).min(h);
                if blocks < crate::MIN_BLOCKS {
                    continue;
                }
                let size = picture_size(grid, blocks, CELL_PIXELS).unwrap();
                if (w, h) == (7, 7) || (w, h) == (255, 1) || (w, h) == (16, 16) {
                    assert_eq!(frame(&observation(grid, blocks), CELL_PIXELS).dimensions(), size);
                }
            }
        }
    }

    #[test]
    fn a_huge_cell_size_is_refused_before_drawing() {
        let err = picture_size(Grid::default(), 3, 100_000).unwrap_err().to_string();
        assert!(
            err.contains("100000-pixel cells") && err.contains("use smaller cells"),
            "{err}"
        );
        assert!(picture_size(Grid::default(), 3, 600).is_ok());
        assert!(picture_size(Grid::new(16, 16).unwrap(), 3, 1000).is_err());
    }

    #[test]
    fn a_picture_is_written_in_the_format_its_name_says() {
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let obs = observation(Grid::default(), 3);
        for (name, format) in [
            ("w.png", image::ImageFormat::Png),
            ("w.JPG", image::ImageFormat::Jpeg),
            ("w.jpeg", image::ImageFormat::Jpeg),
        ] {
            let path = dir.join(name);
            save_picture(&obs, &OutputPath::check(&path).unwrap(), 20).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(image::guess_format(&bytes).unwrap(), format, "{name}");
            let img = image::load_from_memory(&bytes).unwrap();
            assert_eq!((img.width(), img.height()), frame(&obs, 20).dimensions());
        }
        for name in ["w.bmp", "w", "w.png.txt"] {
            let path = dir.join(name);
            let err = save_picture(&obs, &OutputPath::check(&path).unwrap(), 20).unwrap_err();
            assert!(err.to_string().contains(".png or .jpg"), "{err}");
            assert!(!path.exists());
        }
        assert_eq!(PictureFormat::of(Path::new("-")).unwrap(), PictureFormat::Png);
    }
}
