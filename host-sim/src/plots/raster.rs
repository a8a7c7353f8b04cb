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
    write_with_resolution(&pixmap, path)
}

/// Pixels per metre at [`PNG_DPI`], as a PNG's `pHYs` chunk states it: 11 811.
pub const PNG_PIXELS_PER_METRE: u32 = (PNG_DPI / 0.0254 + 0.5) as u32;

/// The pixmap as an 8-bit RGBA PNG that says its print resolution (`pHYs`), so that a layout
/// program places it at its size in inches rather than at 72 or 96 dpi.
fn write_with_resolution(pixmap: &Pixmap, path: &Path) -> Result<(), SceneError> {
    let cannot = |e: &dyn std::fmt::Display| {
        SceneError::new(path.display().to_string(), format!("cannot write: {e}"))
    };
    let file = std::fs::File::create(path).map_err(|e| cannot(&e))?;
    let mut encoder = png::Encoder::new(
        std::io::BufWriter::new(file),
        pixmap.width(),
        pixmap.height(),
    );
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_pixel_dims(Some(png::PixelDimensions {
        xppu: PNG_PIXELS_PER_METRE,
        yppu: PNG_PIXELS_PER_METRE,
        unit: png::Unit::Meter,
    }));
    // tiny-skia keeps premultiplied alpha; a PNG's is straight.
    let data: Vec<u8> = pixmap
        .pixels()
        .iter()
        .flat_map(|p| {
            let c = p.demultiply();
            [c.red(), c.green(), c.blue(), c.alpha()]
        })
        .collect();
    let mut writer = encoder.write_header().map_err(|e| cannot(&e))?;
    writer.write_image_data(&data).map_err(|e| cannot(&e))?;
    writer.finish().map_err(|e| cannot(&e))
}
