use super::*;
use crate::atmosphere::Atmosphere;

fn air(h: f64) -> Air {
    Air::new(h, Atmosphere::nrlmsis21().composition(h), AmbientTable::get().at(h))
}

#[test]
fn placeholder_solves() {
    let e = solve(1e3, &air(110.0));
    assert!(e.per_ion_pair.iter().all(|x| x.is_finite()));
}
