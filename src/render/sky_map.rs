//! The sky the camera sees behind everything, as an equirectangular
//! radiance map for other renderers ([`sky_map`], `aurora sky`): the
//! airglow (`airglow.rs`) and the stars (`sky.rs`), each seen from the
//! scene's camera position with the air's extinction, exactly as `aurora
//! render` draws them, in the layout Blender's Environment Texture reads
//! (`sky.rs`: the centre column faces +x, the top row the zenith, u
//! growing towards -y). Rendered by the renderer itself through an
//! equirectangular camera at the camera's position looking along +x with
//! +z up, whose pixel `(i, j)` looks where the map's pixel `(i, j)` is
//! read: one sample at each pixel centre, no volume, no terrain (the other
//! renderer has its own), and without `background.radiance` and
//! `background.image`, which the other renderer adds itself. Stars keep
//! their flux over the map's pixels, drawn as the render draws them (the
//! reference lens's PSF, the same size in angle, integrated over the map's
//! pixels: `star_psf.rs`); an orthographic scene camera's map has none, as
//! its render has none.

use super::image::Image;
use super::integrator::render_prepared;
use super::prepared::Prepared;
use super::settings::{RenderError, RenderSettings, Volume};
use crate::scene::{Camera, Projection, TerrainKind};
use crate::util::progress::Progress;

/// The widest map, pixels (the height is half the width).
pub const MAX_SKY_WIDTH: usize = 16384;

/// The equirectangular sky map of `settings` (module doc), `width` x
/// `width / 2` pixels, RGBA with alpha 0.
pub fn sky_map(settings: &RenderSettings, width: usize, progress: &dyn Progress) -> Result<Image, RenderError> {
    if !(8..=MAX_SKY_WIDTH).contains(&width) || !width.is_multiple_of(2) {
        return Err(RenderError::Settings(format!("sky map width {width}: must be an even number in [8, {MAX_SKY_WIDTH}]")));
    }
    let mut s = settings.clone();
    // An orthographic view shows no stars (`sky.rs`).
    s.background.stars &= s.camera.projection != Projection::Orthographic;
    let p = s.camera.position;
    s.camera = Camera {
        position: p,
        look_at: [p[0] + 1.0, p[1], p[2]],
        up: [0.0, 0.0, 1.0],
        projection: Projection::Equirectangular,
        // Not used by the panorama; any value its checks accept.
        fov_deg: 90.0,
        ..s.camera
    };
    s.render.width = width;
    s.render.height = width / 2;
    s.render.spp = 1;
    s.terrain.kind = TerrainKind::None;
    s.background.radiance = [0.0; 3];
    s.background.image = None;
    let prepared = Prepared::new(&s, &Volume::default())?;
    render_prepared(&prepared, progress)
}
