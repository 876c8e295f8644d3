//! PNG copies of the report's SVG figures, rendered by resvg (pure Rust; text uses the system's fonts).

use super::figures::Figure;
use crate::atomic;
use anyhow::Context;
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};

/// Pixels per SVG unit: 2 gives crisp figures on high-density screens and in documents.
const SCALE: f32 = 2.0;

/// Renders one SVG document to PNG bytes.
pub fn render(svg: &str, options: &usvg::Options<'_>) -> anyhow::Result<Vec<u8>> {
    let tree = usvg::Tree::from_str(svg, options).context("parsing the figure's SVG")?;
    let size = tree.size().to_int_size().scale_by(SCALE).context("figure size")?;
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).context("allocating the image")?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::from_scale(SCALE, SCALE), &mut pixmap.as_mut());
    pixmap.encode_png().context("encoding PNG")
}

/// Rendering options with the system's fonts; the figures' generic `sans-serif` maps to the first sans-serif
/// family found (DejaVu Sans, Liberation Sans, …), or to any family when there is none.
pub fn options() -> usvg::Options<'static> {
    let mut options = usvg::Options::default();
    let db = options.fontdb_mut();
    db.load_system_fonts();
    let families: Vec<String> = db.faces().flat_map(|f| f.families.iter().map(|(name, _)| name.clone())).collect();
    let pick = ["DejaVu Sans", "Liberation Sans", "Noto Sans", "Arial", "Helvetica"]
        .iter()
        .find(|want| families.iter().any(|f| f == *want))
        .map(|s| s.to_string())
        .or_else(|| families.iter().find(|f| f.contains("Sans") && !f.contains("Mono")).cloned())
        .or_else(|| families.first().cloned());
    if let Some(family) = pick {
        db.set_sans_serif_family(family.clone());
        options.font_family = family;
    }
    options
}

/// Every figure a report can draw (`figures::all`), by id: the PNG files a report owns in its folder.
pub const FIGURE_IDS: &[&str] =
    &["ladder", "overlay-worst", "overlay-typical", "flower", "heat-map", "growth", "ranking"];

/// Writes `DIR/<figure id>.png` for every figure (atomically) and removes the figures of [`FIGURE_IDS`]
/// that this report does not draw (an earlier report's, which would pass for this one's); other files in
/// `DIR` stay. Returns the paths written.
pub fn write_all(figures: &[Figure], dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let options = options();
    let mut written = Vec::with_capacity(figures.len());
    for f in figures {
        anyhow::ensure!(FIGURE_IDS.contains(&f.id.as_str()), "figure {} is missing from png::FIGURE_IDS (a bug)", f.id);
        let path = dir.join(format!("{}.png", f.id));
        let bytes = render(&f.svg, &options).with_context(|| format!("figure {}", f.id))?;
        atomic::write_atomic(&path, &bytes).with_context(|| format!("writing {}", path.display()))?;
        written.push(path);
    }
    for id in FIGURE_IDS.iter().filter(|id| !figures.iter().any(|f| f.id == **id)) {
        let stale = dir.join(format!("{id}.png"));
        match std::fs::remove_file(&stale) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("removing {} (an earlier report's figure)", stale.display()));
            }
            _ => {}
        }
    }
    Ok(written)
}
