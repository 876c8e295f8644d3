//! PNG copies of the report's SVG figures, rendered by resvg (pure Rust; text uses the system's fonts).

use super::figures::Figure;
use crate::atomic;
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};

/// Why one figure could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The SVG does not parse.
    #[error("parsing the figure's SVG")]
    Parse(#[source] usvg::Error),
    /// The scaled size is no image size.
    #[error("figure size")]
    Size,
    /// The image could not be allocated.
    #[error("allocating the image")]
    Allocate,
    /// The PNG encoder failed (its error type, `png::EncodingError`, is not re-exported by resvg).
    #[error("encoding PNG")]
    Encode(#[source] Box<dyn std::error::Error + Send + Sync>),
}

/// Why the PNG figures could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PngError {
    /// The folder could not be created.
    #[error("creating {}", dir.display())]
    CreateDir {
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A figure id that [`FIGURE_IDS`] does not list (a bug).
    #[error("figure {id} is missing from png::FIGURE_IDS (a bug)")]
    UnknownFigure {
        /// The figure's id.
        id: String,
    },
    /// A figure could not be rendered.
    #[error("figure {id}")]
    Render {
        /// The figure's id.
        id: String,
        /// Why.
        source: RenderError,
    },
    /// A PNG file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// An earlier report's figure could not be removed.
    #[error("removing {} (an earlier report's figure)", path.display())]
    RemoveStale {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// Pixels per SVG unit: 2 gives crisp figures on high-density screens and in documents.
const SCALE: f32 = 2.0;

/// Renders one SVG document to PNG bytes.
pub fn render(svg: &str, options: &usvg::Options<'_>) -> Result<Vec<u8>, RenderError> {
    let tree = usvg::Tree::from_str(svg, options).map_err(RenderError::Parse)?;
    let size = tree.size().to_int_size().scale_by(SCALE).ok_or(RenderError::Size)?;
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).ok_or(RenderError::Allocate)?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::from_scale(SCALE, SCALE), &mut pixmap.as_mut());
    pixmap.encode_png().map_err(|e| RenderError::Encode(Box::new(e)))
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
pub const FIGURE_IDS: &[&str] = &[
    "ladder",
    "overlay-worst",
    "overlay-typical",
    "flower",
    "heat-map",
    "growth",
    "trust-ellipses",
    "trust-growth",
    "ranking",
];

/// Writes `DIR/<figure id>.png` for every figure (atomically) and removes the figures of [`FIGURE_IDS`]
/// that this report does not draw (an earlier report's, which would pass for this one's); other files in
/// `DIR` stay. Returns the paths written.
pub fn write_all(figures: &[Figure], dir: &Path) -> Result<Vec<PathBuf>, PngError> {
    std::fs::create_dir_all(dir).map_err(|source| PngError::CreateDir { dir: dir.to_path_buf(), source })?;
    let options = options();
    let mut written = Vec::with_capacity(figures.len());
    for f in figures {
        if !FIGURE_IDS.contains(&f.id.as_str()) {
            return Err(PngError::UnknownFigure { id: f.id.clone() });
        }
        let path = dir.join(format!("{}.png", f.id));
        let bytes = render(&f.svg, &options).map_err(|source| PngError::Render { id: f.id.clone(), source })?;
        atomic::write_atomic(&path, &bytes).map_err(|source| PngError::Write { path: path.clone(), source })?;
        written.push(path);
    }
    for id in FIGURE_IDS.iter().filter(|id| !figures.iter().any(|f| f.id == **id)) {
        let stale = dir.join(format!("{id}.png"));
        match std::fs::remove_file(&stale) {
            Err(source) if source.kind() != std::io::ErrorKind::NotFound => {
                return Err(PngError::RemoveStale { path: stale, source });
            }
            _ => {}
        }
    }
    Ok(written)
}
