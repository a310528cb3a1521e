//! Where a precipitating electron's energy goes with altitude: the
//! spectra ([`spectrum`]: Maxwellian, monoenergetic, accelerated; a
//! curtain's populations in [`curtain_spectrum`]), Fang et al. (2010)'s
//! parameterisation ([`fang`]), its low-energy shape calibrated to NCAR
//! GLOW ([`glow_calibration`]), and the continuous-slowing-down
//! alternative ([`csda`]).

pub mod csda;
pub mod curtain_spectrum;
pub mod fang;
pub mod glow_calibration;
pub mod spectrum;
