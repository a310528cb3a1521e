//! A curtain's electron populations and their spectra: the one place that
//! reads `[[curtain]]`'s spectrum keys.
//!
//! An arc's **body** (Knudsen et al. 2001: 5-20 km wide) carries the
//! curtain's spectrum (`spectrum`, `char_energy_kev`, `potential_kv`) with
//! `soft_fraction` of its energy flux in a soft Maxwellian
//! (`soft_energy_kev`: the red tops). Its **filaments** (0.05-0.2 km;
//! Maggs & Davis 1968, Borovsky 1993, Dahlgren et al. 2012) are where the
//! field-aligned current is strongest: the same source accelerated through
//! `filament_potential_kv` more of drop (Evans 1974), without the soft part.
//! Each beam belongs to one population (`crate::pipeline::beams`), which
//! fixes its deposition and its sampled energy.

use super::fang::{maxwellian, Component, SpectrumDeposition};
use super::spectrum::Spectrum;
use crate::scene::{Curtain, SpectrumShape};
use rand::Rng;
use std::sync::Arc;

/// Which of a curtain's electrons a beam carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Population {
    #[default]
    Body,
    Filaments,
}

/// The hard spectrum of `population` (module documentation).
pub fn hard_spectrum(c: &Curtain, population: Population) -> Spectrum {
    let extra = match population {
        Population::Body => 0.0,
        Population::Filaments => c.filament_potential_kv,
    };
    match c.spectrum {
        SpectrumShape::Monoenergetic => Spectrum::Monoenergetic { e_kev: c.char_energy_kev + extra },
        SpectrumShape::Maxwellian if extra == 0.0 => Spectrum::Maxwellian { e0_kev: c.char_energy_kev },
        SpectrumShape::Maxwellian => Spectrum::Accelerated { e0_kev: c.char_energy_kev, potential_kv: extra },
        SpectrumShape::Accelerated => Spectrum::Accelerated { e0_kev: c.char_energy_kev, potential_kv: c.potential_kv + extra },
    }
}

/// The share of `population`'s energy flux in the soft Maxwellian.
fn soft_share(c: &Curtain, population: Population) -> f64 {
    match population {
        Population::Body => c.soft_fraction,
        Population::Filaments => 0.0,
    }
}

/// The components of `population`'s spectrum by energy flux.
pub fn components(c: &Curtain, population: Population) -> [Component; 2] {
    let soft = soft_share(c, population);
    [Component { share: 1.0 - soft, spectrum: hard_spectrum(c, population) }, maxwellian(soft, c.soft_energy_kev)]
}

/// `G(m)` of `population`, Fang 2010 over its spectrum (cached).
pub fn deposition(c: &Curtain, population: Population) -> Arc<SpectrumDeposition> {
    SpectrumDeposition::cached(&components(c, population))
}

/// One energy of `population`'s spectrum weighted by energy flux, for the
/// `sampled` and `csda` beams: first the soft or the hard part (one
/// uniform), then its energy (`Spectrum::sample_energy`).
pub fn sample_energy(c: &Curtain, population: Population, r: &mut impl Rng) -> f64 {
    if r.random::<f64>() < soft_share(c, population) {
        Spectrum::Maxwellian { e0_kev: c.soft_energy_kev }.sample_energy(r)
    } else {
        hard_spectrum(c, population).sample_energy(r)
    }
}

/// Whether a curtain has filaments.
pub fn has_filaments(c: &Curtain) -> bool {
    c.filament_energy_flux > 0.0
}
