//! One beam as data: where it starts and what it carries ([`BeamStart`]),
//! what its curtain shares with it ([`BeamContext`], with the deposition
//! model, [`DepositModel`]), and what its walk leaves ([`BeamTrace`], into
//! [`BeamBuffers`], with its [`EndReason`]). The walk is
//! [`super::walk`]'s; a step's photon is [`super::emit`]'s.

use crate::geometry::earth::Earth;
use crate::physics::atmosphere::Atmosphere;
use crate::physics::deposition::fang::{IonizationProfile, MonoDeposition, SpectrumDeposition};
use crate::physics::emission::line_colour::ColourTable;
use crate::physics::emission::line_table::LineTable;
use crate::physics::geomagnetic_field::MagneticField;
use crate::pipeline::deposit::{Photon, StepDeposit};
use crate::pipeline::footprint::Footprint;
use crate::pipeline::motion::Wave;
use crate::pipeline::red_trail::TrailSample;
use crate::scene::BeamParams;
use glam::DVec3;

/// Why a beam stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndReason {
    /// Its field-line foot left the footprint: CSDA, the density at or below
    /// threshold; Fang models, the footprint's box enlarged by its own size
    /// on every side (runaway steps only).
    LeftFootprint,
    /// The atmosphere absorbed all its energy.
    EnergySpent,
    /// It took the maximum number of steps (1 / dt for CSDA,
    /// [`FANG_MAX_STEPS`](super::walk::FANG_MAX_STEPS) for the Fang models).
    MaxSteps,
    /// It went below the atmosphere's table (Fang models).
    Bottom,
}

/// Where a beam starts and what it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamStart {
    pub position: DVec3,
    /// The beam's electron energy (sampled and CSDA models; unused by the
    /// expected model, which carries the whole spectrum).
    pub energy_kev: f64,
    /// Electron power of the beam, keV/s (at the frame's time: with
    /// pulsation, `base_power_kev_s` times the flux's modulation).
    pub power_kev_s: f64,
    /// The beam's power without the pulsation, keV/s.
    pub base_power_kev_s: f64,
    /// The pulsation at the beam's start as a wave in time, when each line
    /// follows it through its lifetime (`crate::physics::emission::line_table`); `None` when nothing
    /// pulses or the colour is a colour map (the colour then follows
    /// `power_kev_s`).
    pub wave: Option<Wave>,
    /// Colour altitude offset of this beam, km (the report's low-frequency
    /// colour noise; it shifts colour, not intensity).
    pub colour_offset_km: f64,
    /// Energy flux entering the atmosphere at the beam's foot, keV cm^-2
    /// s^-1: the curtain's peak flux times the footprint's density at the
    /// start (relative to its peak) times the pulsation. With the curtain's
    /// [`IonizationProfile`] it gives the local ionization rate at every
    /// deposit, which the chemistry's colours need.
    pub flux_kev_cm2_s: f64,
    /// The curtain's electrons the beam carries: the arc's body or its
    /// filaments (`crate::physics::deposition::curtain_spectrum`).
    pub population: crate::physics::deposition::curtain_spectrum::Population,
}

/// The result of tracing one beam.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamTrace {
    pub photons: Vec<Photon>,
    /// Per photon, the powers of `BeamContext::line_outputs` in that order,
    /// photons per second times [`R_PER_KM_SCALE`](crate::physics::emission::line_table::R_PER_KM_SCALE) (empty without outputs).
    pub line_power: Vec<f32>,
    /// One entry per photon, in step order: the step's altitudes and the
    /// power it deposited.
    pub deposits: Vec<StepDeposit>,
    /// Power the beam's model says is backscattered (never deposited:
    /// `P (1 - D(inf))`), keV/s; 0 for CSDA.
    pub backscatter_kev_s: f64,
    /// Power the model deposits above the top of the beam's deposit (at
    /// most [`ABOVE_START_TOL`](super::walk::ABOVE_START_TOL) of its total, above [`above_start_top`](super::walk::above_start_top)),
    /// outside the bake, keV/s; 0 for CSDA.
    pub above_top_kev_s: f64,
    /// Power the beam still carried when it stopped, keV/s.
    pub undeposited_kev_s: f64,
    pub end: EndReason,
    /// Position after the last accepted step.
    pub end_position: DVec3,
    /// Deflection points, including the start (for tests and debugging).
    pub path: Vec<DVec3>,
    /// The last photon's end: in the walk's frame and mapped to the scene
    /// (f32), for the next step, which starts there ([`super::emit::emit`]).
    pub(super) last_end: Option<(DVec3, [f32; 3])>,
}

impl BeamTrace {
    /// A beam at `p` that has not stepped yet (its path starting at `p` if
    /// recorded), `backscatter_kev_s` set by its model, appending to `bufs`.
    pub(super) fn begin(p: DVec3, backscatter_kev_s: f64, record_path: bool, bufs: BeamBuffers) -> Self {
        let mut out = BeamTrace {
            photons: bufs.photons,
            line_power: bufs.line_power,
            deposits: bufs.deposits,
            backscatter_kev_s,
            above_top_kev_s: 0.0,
            undeposited_kev_s: 0.0,
            end: EndReason::MaxSteps,
            end_position: p,
            path: Vec::new(),
            last_end: None,
        };
        if record_path {
            out.path.push(p);
        }
        out
    }
}

/// Vectors a trace appends its photons, line powers and deposits to
/// ([`trace_beam_into`](super::walk::trace_beam_into)): empty for a beam of its own, or those of the
/// beams before it, so many beams fill one allocation instead of each
/// growing its own.
#[derive(Clone, Debug, Default)]
pub struct BeamBuffers {
    pub photons: Vec<Photon>,
    pub line_power: Vec<f32>,
    pub deposits: Vec<StepDeposit>,
}

/// How a curtain's beams deposit energy (module doc).
#[derive(Clone, Copy, Debug)]
pub enum DepositModel<'a> {
    /// The curtain's whole spectrum on every beam.
    Expected(&'a SpectrumDeposition),
    /// One energy per beam, Fang 2010 monoenergetic.
    Sampled(&'a MonoDeposition),
    /// One energy per beam, continuous slowing down.
    Csda,
}

/// Everything a beam needs that is shared by the beams of one curtain.
pub struct BeamContext<'a> {
    pub atmosphere: &'a Atmosphere,
    pub model: DepositModel<'a>,
    pub colour: &'a ColourTable,
    pub field: MagneticField,
    pub params: &'a BeamParams,
    pub footprint: &'a Footprint,
    /// Footprint density at or below which a beam has left the curtain.
    pub threshold: f64,
    /// Keep the path (off in the bake: memory).
    pub record_path: bool,
    /// The lines one at a time (`crate::pipeline::beams::TraceParams::lines`) and
    /// the ones that leave per-line photon powers.
    pub lines: Option<&'a LineTable>,
    pub line_outputs: &'a [usize],
    /// The red trail's sample this trace makes (`crate::pipeline::red_trail`; with
    /// `lines`): `None` keeps every line at the bake's time.
    pub trail: Option<TrailSample>,
    /// The curtain spectrum's ionization per unit flux over altitude, when
    /// the colours need the ionization rate (the chemistry); `None` leaves
    /// q = 0 on every deposit.
    pub ionization: Option<&'a IonizationProfile>,
    /// The Earth: the walk is in its curved frame (ground coordinates and
    /// altitude, `crate::geometry::earth`), and each photon is mapped to the scene
    /// frame as it is made ([`deposit`](super::emit::deposit)); the identity when flat.
    pub earth: Earth,
}
