//! `lgh merge`: joins the pieces of a frame that `lgh render --tile` (or `--region`) wrote,
//! after checking that they belong to one frame, have the same settings and cover it once.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use clap::Args;
use glam::Vec3;
use lgh_render::Image;

use crate::render_cmd::piece::{self, FORMAT, PieceInfo};

/// Join the pieces of one frame.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The pieces (.exr files written by `lgh render --tile I/N` or `--region`, each with its
    /// side file PIECE.exr.json), in any order.
    #[arg(required = true)]
    pub pieces: Vec<PathBuf>,
    /// The frame: .exr (linear) or .png (tone-mapped with the exposure the pieces record).
    #[arg(long, short)]
    pub out: PathBuf,
}

/// Reads a piece's side file.
fn info(path: &Path) -> Result<PieceInfo> {
    let side = piece::side_path(path);
    let text = std::fs::read_to_string(&side).map_err(|e| {
        anyhow!(
            "{}: cannot read its side file {}: {e}",
            path.display(),
            side.display()
        )
    })?;
    let info: PieceInfo = serde_json::from_str(&text).map_err(|e| {
        anyhow!(
            "{}: not a side file of lgh render --tile: {e}",
            side.display()
        )
    })?;
    if info.format != FORMAT {
        bail!(
            "{}: format {:?}, expected {FORMAT:?}",
            side.display(),
            info.format
        );
    }
    Ok(info)
}

pub fn run(args: &MergeArgs) -> Result<()> {
    lgh_render::image::check_output_path(&args.out)?;
    let infos = args
        .pieces
        .iter()
        .map(|p| info(p))
        .collect::<Result<Vec<_>>>()?;
    let (first, first_path) = (&infos[0], &args.pieces[0]);
    let [w, h] = first.frame_size;
    let mut covered = 0u64;
    for (i, (inf, path)) in infos.iter().zip(&args.pieces).enumerate() {
        let other = |what: &str| {
            anyhow!(
                "{}: {what} differs from {}'s: not a piece of the same frame",
                path.display(),
                first_path.display()
            )
        };
        if inf.frame_size != first.frame_size {
            return Err(other("the frame size"));
        }
        if inf.frame != first.frame {
            return Err(other("the frame number"));
        }
        if inf.scene != first.scene {
            return Err(other("the scene"));
        }
        if inf.settings != first.settings || inf.exposure != first.exposure {
            return Err(other("the settings"));
        }
        inf.region
            .check(w, h)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        if let Some(j) = infos[..i]
            .iter()
            .position(|o| o.region.overlaps(&inf.region))
        {
            bail!(
                "{}: overlaps {} (each pixel must come from one piece)",
                path.display(),
                args.pieces[j].display()
            );
        }
        covered += u64::from(inf.region.width()) * u64::from(inf.region.height());
    }
    if covered != u64::from(w) * u64::from(h) {
        bail!(
            "the pieces cover {covered} of the frame's {} pixels: a piece is missing",
            u64::from(w) * u64::from(h)
        );
    }
    let mut pixels = vec![Vec3::ZERO; w as usize * h as usize];
    for (inf, path) in infos.iter().zip(&args.pieces) {
        let img = Image::load(path)?;
        if (img.width, img.height) != (inf.region.width(), inf.region.height()) {
            bail!(
                "{}: {}x{} pixels where its side file says {}x{}",
                path.display(),
                img.width,
                img.height,
                inf.region.width(),
                inf.region.height()
            );
        }
        piece::paste(&mut pixels, w, &img, &inf.region);
    }
    Image::from_pixels(w, h, pixels).save(&args.out, first.exposure)?;
    Ok(())
}
