//! PNG from the figure's own SVG (resvg): anti-aliased lines and text at print resolution, and the
//! same drawing as the SVG, pixel for point.

use std::path::Path;
use std::sync::OnceLock;

use resvg::tiny_skia::{Pixmap, Transform};
use resvg::usvg::{Options, Tree, fontdb};

use super::{font_bytes, plot_error};
use crate::scene::SceneError;

/// Pixels per inch of a PNG: print resolution.
pub const PNG_DPI: f64 = 300.0;

/// What an SVG length without unit is, per inch (CSS pixels).
const SVG_PX_PER_IN: f64 = 96.0;

/// The font database: the plot font, also the generic `sans-serif` that plotters names.
fn fonts() -> Result<&'static fontdb::Database, SceneError> {
    static FONTS: OnceLock<Result<fontdb::Database, String>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let bytes = font_bytes().map_err(|e| e.reason)?;
            let mut db = fontdb::Database::new();
            db.load_font_data(bytes.to_vec());
            let family = db
                .faces()
                .next()
                .and_then(|f| f.families.first())
                .map(|(name, _)| name.clone())
                .ok_or("the plot font has no family name")?;
            db.set_sans_serif_family(family);
            Ok(db)
        })
        .as_ref()
        .map_err(|e| SceneError::new("plots", e.clone()))
}

/// Writes `svg` (a complete SVG document with its physical size) as a PNG at [`PNG_DPI`].
pub(super) fn write_png(svg: &str, path: &Path) -> Result<(), SceneError> {
    let mut options = Options::default();
    *options.fontdb_mut() = fonts()?.clone();
    let tree = Tree::from_str(svg, &options).map_err(plot_error)?;
    // usvg sizes the tree in CSS pixels, 96 an inch.
    let zoom = (PNG_DPI / SVG_PX_PER_IN) as f32;
    let size = tree.size();
    let (w, h) = (
        (size.width() * zoom).ceil() as u32,
        (size.height() * zoom).ceil() as u32,
    );
    let mut pixmap =
        Pixmap::new(w, h).ok_or_else(|| plot_error(format!("{w} x {h} pixels: no image")))?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        Transform::from_scale(zoom, zoom),
        &mut pixmap.as_mut(),
    );
    pixmap
        .save_png(path)
        .map_err(|e| SceneError::new(path.display().to_string(), format!("cannot write: {e}")))
}
