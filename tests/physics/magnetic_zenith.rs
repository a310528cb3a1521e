//! The magnetic zenith over a site: the direction IGRF-14 gives at the
//! site (computed here from the model and the site's WGS 84 frame) is the
//! direction the bake's beams follow where they start above the site.

use aurora::geometry::astronomy::site::Site;
use aurora::geometry::astronomy::time::Utc;
use aurora::physics::igrf::Igrf;
use aurora::pipeline::plan::BakePlan;
use aurora::scene::presets;
use aurora::util::progress::NoProgress;
use glam::DVec3;

#[test]
fn the_beams_over_the_site_follow_igrf_to_the_magnetic_zenith() {
    let scene = presets::by_name("tromso").unwrap();
    let p = scene.site.clone().unwrap();
    let plan = BakePlan::new(&scene, &NoProgress);
    let beams = plan.field_at([0.0, 0.0]).b;

    let site = Site::new(p.latitude_deg, p.longitude_deg, p.height_km).unwrap();
    let igrf = Igrf::at(Utc::parse_rfc3339(&p.utc).unwrap().plus_seconds(scene.animation.time_s)).unwrap();
    let [e, n, u] = site.basis();
    let zenith_at = |h: f64| {
        let b = igrf.field_itrs(site.itrs_km() + h * u);
        -DVec3::new(b.dot(e), b.dot(n), b.dot(u)).normalize()
    };
    let top = zenith_at(scene.beams.top_km);
    let angle = (-beams).angle_between(top).to_degrees();
    assert!(angle < 0.05, "the beams are {angle} degrees from the magnetic zenith");
    // Tromso's magnetic zenith: 11.5 degrees from the zenith, toward the
    // south-south-west (the field dips 78.5 degrees toward the north-north-east).
    let from_zenith = top.angle_between(DVec3::Z).to_degrees();
    assert!(from_zenith > 11.0 && from_zenith < 12.0 && top.y < 0.0 && top.x < 0.0, "{top} {from_zenith}");
    // From the ground to the beams' top the line turns by a small angle.
    let turn = zenith_at(0.0).angle_between(top).to_degrees();
    eprintln!("beams vs magnetic zenith: {angle:.2e} deg; ground vs top ({} km): {turn:.3} deg", scene.beams.top_km);
    assert!(turn < 0.5, "{turn}");
}
