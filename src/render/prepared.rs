//! What is built once per scene, camera and medium before any pixel is
//! traced ([`Prepared`]): the camera model, the medium (`medium/`), the
//! terrain, the terrain's emission sampler (`shadow.rs`), the sky and the
//! air between the volume and the camera (`crate::physics::air_extinction`), with the
//! settings they were built for. The emission sampler taken from the
//! medium is built when a shadow ray first needs one ([`Prepared::sampler`]):
//! a picture that never sees lit terrain, and a keogram, never pay for it. Every way to make or change one
//! ([`Prepared::new`], [`Prepared::with_medium`], [`Prepared::reuse`],
//! [`Prepared::set_volume_scales`], [`Prepared::set_image`]) runs the same
//! checks, so the pixel loop (`integrator.rs`) never sees a setting out of
//! range or a medium past the memory check.

use super::airglow::Airglow;
use super::medium::Medium;
use super::settings::{Integration, RenderError, RenderSettings, Volume};
use super::shadow::{EmissionSampler, ShadowScene};
use super::sky::Sky;
use super::terrain::TerrainModel;
use crate::geometry::camera::CameraModel;
use crate::grid::Grid;
use crate::physics::air_extinction::{Air, Extinction};
use glam::DVec3;
use std::sync::OnceLock;

/// A scene ready to render: camera, medium, terrain and emission sampler.
pub struct Prepared {
    pub(super) camera: CameraModel,
    pub(super) medium: Medium,
    pub(super) terrain: TerrainModel,
    /// Set when built from an emission grid; else empty until the first
    /// call of [`Prepared::sampler`], which builds it from the medium.
    sampler: OnceLock<Option<EmissionSampler>>,
    pub(super) sky: Sky,
    /// The air's transmittance (`[sky] extinction`), None without it.
    pub(super) air: Option<Extinction>,
    /// The airglow's radiance per direction (`[airglow]`), None when off.
    pub(super) airglow: Option<Airglow>,
    pub(super) settings: RenderSettings,
    /// The velocity grid of the motion blur (`render.shutter_s`), if given.
    pub(super) velocity: Option<super::medium::velocity::Velocity>,
}

impl Prepared {
    /// The velocity grid `v` the motion blur of `render.shutter_s` advects
    /// the lookups along (`medium::velocity`).
    pub fn with_velocity(mut self, v: Grid<[f32; 3]>) -> Result<Prepared, RenderError> {
        self.velocity = Some(super::medium::velocity::Velocity::new(v)?);
        Ok(self)
    }

    /// Validates the settings and builds everything the pixel loop reads.
    pub fn new(settings: &RenderSettings, volume: &Volume<'_>) -> Result<Prepared, RenderError> {
        let camera = Self::check(settings)?;
        let medium = Medium::new(volume.density, volume.emission, settings.volume.density_scale, settings.volume.emission_scale)?;
        Self::assemble(settings, camera, medium, volume.emission)
    }

    /// [`Prepared::new`] with a medium already built (for instance straight
    /// from a file, `crate::app::vdb_for_render::read_render_medium`), its scales set
    /// to the settings'. `emission` is the emission grid for the terrain's
    /// emission sampler if the caller has it; without it the sampler is
    /// built from the medium (the same sampler) when first needed
    /// ([`Prepared::sampler`]).
    pub fn with_medium(settings: &RenderSettings, mut medium: Medium, emission: Option<&Grid<[f32; 3]>>) -> Result<Prepared, RenderError> {
        let camera = Self::check(settings)?;
        medium.set_scales(settings.volume.density_scale, settings.volume.emission_scale)?;
        Self::assemble(settings, camera, medium, emission)
    }

    /// The structures for `settings` and the grids in `volume`, reusing
    /// `old`'s parts whose inputs are unchanged (`grids_changed`: `volume`
    /// holds other grids than the ones `old` was built from): the same
    /// `Prepared` as [`Prepared::new`], with the same checks, built part by
    /// part:
    /// - the medium (the costly part): kept unless the grids changed; a
    ///   `[volume]` edit only sets its scales ([`Prepared::set_volume_scales`],
    ///   applied at lookup);
    /// - the emission sampler: with the medium, unless the terrain appeared or
    ///   vanished;
    /// - the terrain model: kept unless `[terrain]` other than `albedo` (read
    ///   per hit from the settings) changed; the sky, unless `[background]` or
    ///   the seed did; the camera, unless `[camera]` or the size did.
    ///
    /// Without `old`, or with another integration or shadow-ray count,
    /// [`Prepared::new`] builds everything.
    pub fn reuse(
        old: Option<Prepared>,
        grids_changed: bool,
        settings: &RenderSettings,
        volume: &Volume<'_>,
    ) -> Result<Prepared, RenderError> {
        let s = settings;
        let Some(old) =
            old.filter(|o| o.settings.integration == s.integration && o.settings.render.shadow_samples == s.render.shadow_samples)
        else {
            return Prepared::new(s, volume);
        };
        Self::check_settings(s)?;
        let o = old.settings;
        let had_terrain = !matches!(old.terrain, TerrainModel::None);
        // The medium holds the grids' unit values and applies the volume scales
        // at lookup, so a `[volume]` edit keeps it: `set_volume_scales` below.
        let medium = if grids_changed {
            Medium::new(volume.density, volume.emission, s.volume.density_scale, s.volume.emission_scale)?
        } else {
            old.medium
        };
        let (mut t_old, mut t_new) = (o.terrain.clone(), s.terrain.clone());
        (t_old.albedo, t_new.albedo) = ([0.0; 3], [0.0; 3]);
        let terrain = if t_old == t_new && o.base_dir == s.base_dir && o.earth_radius_km == s.earth_radius_km {
            old.terrain
        } else {
            TerrainModel::on_earth(&s.terrain, s.base_dir.as_deref(), s.earth_radius_km)?
        };
        let sampler = if !grids_changed && had_terrain == !matches!(terrain, TerrainModel::None) {
            old.sampler
        } else {
            emission_sampler(&terrain, volume.emission, &medium)
        };
        // With a site the sky also follows the hour, the observer and the air.
        let same_sky = o.background == s.background
            && o.seed == s.seed
            && o.base_dir == s.base_dir
            && o.site == s.site
            && (s.site.is_none()
                || (o.time_s == s.time_s && o.observer == s.observer && o.sky == s.sky && o.camera.position == s.camera.position));
        let sky = if same_sky { old.sky } else { Sky::of_settings(s)? };
        let camera = if o.camera == s.camera && (old.camera.width, old.camera.height) == (s.render.width, s.render.height) {
            old.camera
        } else {
            CameraModel::new(&s.camera, s.render.width, s.render.height)?
        };
        let air = observer_air(s);
        let same_glow = o.airglow == s.airglow
            && o.sky == s.sky
            && o.camera.position == s.camera.position
            && o.earth_radius_km == s.earth_radius_km
            && o.terrain.albedo == s.terrain.albedo;
        let airglow = if same_glow { old.airglow } else { observer_airglow(s) };
        let velocity = if grids_changed { None } else { old.velocity };
        let mut prepared = Prepared { camera, medium, terrain, sampler, sky, air, airglow, settings: s.clone(), velocity };
        if !grids_changed && o.volume != s.volume {
            // The kept medium and sampler still carry the old scales.
            prepared.set_volume_scales(s.volume.density_scale, s.volume.emission_scale)?;
        }
        Ok(prepared)
    }

    /// A `volume.density_scale` / `volume.emission_scale` edit without a
    /// rebuild ([`Medium::set_scales`]; the emission sampler's power
    /// likewise): the same `Prepared` as [`Prepared::new`] with the new
    /// scales (a sampler needed again when the emission scale leaves 0 is
    /// built from the medium). On `Err` nothing changed.
    pub fn set_volume_scales(&mut self, density_scale: f64, emission_scale: f64) -> Result<(), RenderError> {
        self.medium.set_scales(density_scale, emission_scale)?;
        self.settings.volume.density_scale = density_scale;
        self.settings.volume.emission_scale = emission_scale;
        // A sampler not built yet is built from the medium, at its new
        // scale, when it is first needed.
        let Some(built) = self.sampler.get_mut() else { return Ok(()) };
        match (built.as_mut(), self.medium.emission) {
            (Some(s), Some(_)) => {
                if !s.set_scale(emission_scale) {
                    *built = None;
                }
            }
            (Some(_), None) => *built = None,
            (None, Some(_)) if !self.terrain.is_none() => self.sampler = OnceLock::new(),
            (None, _) => {}
        }
        Ok(())
    }

    /// A new image size and sample count (`render.width`, `render.height`,
    /// `render.spp`) with everything else kept: the same `Prepared` as
    /// [`Prepared::new`] with those settings (only the camera depends on
    /// the size). On `Err` nothing changed.
    pub fn set_image(&mut self, width: usize, height: usize, spp: usize) -> Result<(), RenderError> {
        if spp == 0 {
            return Err(RenderError::Settings("render.spp must be at least 1".into()));
        }
        self.camera = CameraModel::new(&self.settings.camera, width, height)?;
        let r = &mut self.settings.render;
        (r.width, r.height, r.spp) = (width, height, spp);
        Ok(())
    }

    /// The settings the structures were built for.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    pub fn camera(&self) -> &CameraModel {
        &self.camera
    }

    pub fn medium(&self) -> &Medium {
        &self.medium
    }

    pub fn terrain(&self) -> &TerrainModel {
        &self.terrain
    }

    /// The terrain's emission sampler (none without a terrain or emission),
    /// built from the medium on the first call when it was not built with
    /// the rest: the same sampler whenever, and on whichever thread, that
    /// call comes (the medium does not change under it).
    pub fn sampler(&self) -> Option<&EmissionSampler> {
        self.sampler
            .get_or_init(|| match (&self.terrain, self.medium.emission) {
                (TerrainModel::None, _) | (_, None) => None,
                _ => EmissionSampler::from_medium(&self.medium),
            })
            .as_ref()
    }

    /// The settings' checks; the camera.
    fn check(settings: &RenderSettings) -> Result<CameraModel, RenderError> {
        Self::check_settings(settings)?;
        let r = &settings.render;
        Ok(CameraModel::new(&settings.camera, r.width, r.height)?)
    }

    /// The settings' checks but the camera's.
    fn check_settings(settings: &RenderSettings) -> Result<(), RenderError> {
        let r = &settings.render;
        let bad = |m: String| Err(RenderError::Settings(m));
        if r.spp == 0 {
            return bad("render.spp must be at least 1".into());
        }
        if settings.render.shadow_samples == 0 {
            return bad("shadow_samples must be at least 1".into());
        }
        if let Integration::FixedStep(h) = settings.integration {
            if !(h.is_finite() && h > 0.0) {
                return bad(format!("fixed step {h} must be finite and > 0"));
            }
        }
        if settings.background.radiance.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return bad(format!("background.radiance {:?} must be finite and >= 0", settings.background.radiance));
        }
        if settings.terrain.albedo.iter().any(|v| !(0.0..=1.0).contains(v)) {
            return bad(format!("terrain.albedo {:?} must be in [0, 1]", settings.terrain.albedo));
        }
        Ok(())
    }

    fn assemble(
        settings: &RenderSettings,
        camera: CameraModel,
        medium: Medium,
        emission: Option<&Grid<[f32; 3]>>,
    ) -> Result<Prepared, RenderError> {
        let terrain = TerrainModel::on_earth(&settings.terrain, settings.base_dir.as_deref(), settings.earth_radius_km)?;
        let sampler = emission_sampler(&terrain, emission, &medium);
        let sky = Sky::of_settings(settings)?;
        let air = observer_air(settings);
        let airglow = observer_airglow(settings);
        Ok(Prepared { camera, medium, terrain, sampler, sky, air, airglow, settings: settings.clone(), velocity: None })
    }

    pub(super) fn shadow_scene(&self) -> ShadowScene<'_> {
        ShadowScene {
            medium: &self.medium,
            terrain: &self.terrain,
            sampler: self.sampler(),
            integration: self.settings.integration,
            air: self.air.as_ref(),
        }
    }

    /// The air's transmittance model, if `[sky] extinction` is on.
    pub fn air(&self) -> Option<&Extinction> {
        self.air.as_ref()
    }
}

/// The air as the camera sees it: the one place the observer's altitude and
/// local up are taken from the camera (`Extinction::for_observer`).
fn observer_air(s: &RenderSettings) -> Option<Extinction> {
    let air = Air::from_sky(&s.sky)?;
    let earth = crate::geometry::earth::Earth::new(s.earth_radius_km);
    let at = DVec3::from_array(s.camera.position);
    Some(Extinction::for_observer_at(air, at, earth.altitude(at), earth.local_up(at), s.line, s.observer))
}

/// The airglow as the camera sees it (`super::airglow`), None when off.
fn observer_airglow(s: &RenderSettings) -> Option<Airglow> {
    let albedo = crate::util::colour::luminance(s.terrain.albedo);
    Airglow::new(&s.airglow, &s.sky, DVec3::from_array(s.camera.position), s.earth_radius_km, s.observer, albedo)
}

/// The terrain's emission sampler: none without a terrain or emission;
/// from the emission grid if the caller has it (built now: the grid is not
/// kept), else left to [`Prepared::sampler`] to build from the medium when
/// first needed (the same sampler).
fn emission_sampler(terrain: &TerrainModel, emission: Option<&Grid<[f32; 3]>>, medium: &Medium) -> OnceLock<Option<EmissionSampler>> {
    match (terrain, emission, medium.emission) {
        (TerrainModel::None, _, _) | (_, _, None) => OnceLock::from(None),
        (_, Some(g), Some(_)) => OnceLock::from(EmissionSampler::new(g, medium)),
        (_, None, Some(_)) => OnceLock::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::{DVec3, IVec3};

    /// Density and emission grids in front of the tests' camera.
    fn grids(k: f32) -> (Grid<f32>, Grid<[f32; 3]>) {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        for x in -6..10 {
            for y in -3..3 {
                for z in 4..12 {
                    let v = ((x * 7 + y * 3 + z) & 7) as f32 * 0.25 * k;
                    d.set(IVec3::new(x, y, z), 0.1 * v);
                    e.set(IVec3::new(x, y, z), [v, 0.5 * v, 0.25]);
                }
            }
        }
        (d, e)
    }

    /// The tests' scene: 16 x 12 pixels, 2 spp, the volume in view.
    fn scene(terrain: crate::scene::TerrainKind) -> crate::scene::Scene {
        let mut scene = crate::scene::Scene::default();
        scene.terrain.kind = terrain;
        scene.terrain.height = 0.5;
        scene.render.width = 16;
        scene.render.height = 12;
        scene.render.spp = 2;
        scene.camera.position = [1.0, -20.0, 4.0];
        scene.camera.look_at = [1.0, 0.0, 2.0];
        scene
    }

    /// The rendered image's bits.
    fn bits(p: &Prepared) -> Vec<u32> {
        let img = crate::render::render_prepared(p, &crate::util::progress::NoProgress).unwrap();
        img.pixels.iter().flat_map(|p| p.map(f32::to_bits)).collect()
    }

    /// A scale edit through `Prepared::set_volume_scales` renders exactly
    /// as a fresh `Prepared::new` with those scales, with and without the
    /// terrain (whose emission sampler is rescaled, dropped at a zero
    /// emission scale and rebuilt from the medium when it leaves 0).
    #[test]
    fn scale_edits_render_as_a_fresh_build() {
        use crate::scene::TerrainKind;
        let (d, e) = grids(1.0);
        let volume = Volume { density: Some(&d), emission: Some(&e) };
        for terrain in [TerrainKind::None, TerrainKind::Plane] {
            let mut settings = RenderSettings::from_scene(&scene(terrain));
            let mut p = Prepared::new(&settings, &volume).unwrap();
            for (ds, es) in [(2.0, 0.5), (0.0, 3.0), (1.5, 0.0), (1.0, 1.0)] {
                settings.volume.density_scale = ds;
                settings.volume.emission_scale = es;
                let fresh = Prepared::new(&settings, &volume).unwrap();
                p.set_volume_scales(ds, es).unwrap();
                assert!(p.medium == fresh.medium, "{terrain:?} {ds} {es}");
                assert_eq!(p.sampler().map(|s| s.power), fresh.sampler().map(|s| s.power));
                let want = bits(&fresh);
                assert!(want.iter().any(|&b| b != 0), "the camera sees the volume");
                assert_eq!(bits(&p), want, "{terrain:?} {ds} {es}");
            }
            if terrain == TerrainKind::Plane {
                assert!(p.sampler().is_some(), "the terrain's sampler is exercised");
            }
        }
    }

    /// `Prepared::reuse` after each kind of edit (camera, size, samples,
    /// background, seed, terrain appearing and vanishing, albedo, volume
    /// scales, new grids) renders exactly as a fresh `Prepared::new` with
    /// the new settings; it runs `new`'s checks (an albedo out of range is
    /// refused although every part could be kept); `set_image` to a
    /// smaller picture and back renders as before, and refuses 0 samples
    /// leaving everything unchanged.
    #[test]
    fn reuse_renders_as_a_fresh_build_with_the_same_checks() {
        use crate::scene::TerrainKind;
        let (d, e) = grids(1.0);
        let (d2, e2) = grids(2.0);
        let (v1, v2) = (Volume { density: Some(&d), emission: Some(&e) }, Volume { density: Some(&d2), emission: Some(&e2) });
        let base = scene(TerrainKind::Plane);
        type Edit = fn(&mut crate::scene::Scene);
        let edits: [(&str, Edit, bool); 10] = [
            ("camera", |s| s.camera.position[2] = 5.0, false),
            ("size", |s| s.render.width = 12, false),
            ("spp", |s| s.render.spp = 3, false),
            ("background", |s| s.background.radiance = [0.01, 0.02, 0.03], false),
            ("seed", |s| s.seed = 99, false),
            ("no terrain", |s| s.terrain.kind = TerrainKind::None, false),
            ("terrain again", |s| s.terrain.kind = TerrainKind::Plane, false),
            ("albedo", |s| s.terrain.albedo = [0.5, 0.4, 0.3], false),
            ("scales", |s| (s.volume.density_scale, s.volume.emission_scale) = (1.5, 0.7), false),
            ("grids", |_| {}, true),
        ];
        let mut scene = base.clone();
        let mut p = Prepared::new(&RenderSettings::from_scene(&scene), &v1).unwrap();
        for (name, edit, new_grids) in edits {
            edit(&mut scene);
            let s = RenderSettings::from_scene(&scene);
            let volume = if new_grids { &v2 } else { &v1 };
            p = Prepared::reuse(Some(p), new_grids, &s, volume).unwrap();
            let fresh = Prepared::new(&s, volume).unwrap();
            assert!(p.medium == fresh.medium, "{name}");
            assert_eq!(p.sampler().map(|s| s.power), fresh.sampler().map(|s| s.power), "{name}");
            let want = bits(&fresh);
            assert!(want.iter().any(|&b| b != 0), "{name}: the camera sees the volume");
            assert_eq!(bits(&p), want, "{name}");
        }
        let mut bad = RenderSettings::from_scene(&scene);
        bad.terrain.albedo = [2.0, 0.0, 0.0];
        let err = Prepared::reuse(Some(p), false, &bad, &v2).err().expect("albedo 2 is refused");
        assert!(matches!(&err, RenderError::Settings(m) if m.contains("terrain.albedo")), "{err}");

        let s = RenderSettings::from_scene(&base);
        let mut p = Prepared::new(&s, &v1).unwrap();
        let want = bits(&p);
        p.set_image(4, 3, 1).unwrap();
        assert_eq!((p.camera().width, p.camera().height, p.settings().render.spp), (4, 3, 1));
        assert_eq!(bits(&p).len(), 4 * 3 * 4);
        assert!(p.set_image(4, 3, 0).is_err() && p.set_image(0, 3, 1).is_err());
        assert_eq!((p.camera().width, p.camera().height, p.settings().render.spp), (4, 3, 1), "unchanged on Err");
        p.set_image(16, 12, 2).unwrap();
        assert_eq!(bits(&p), want);
    }
}
