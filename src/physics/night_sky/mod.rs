//! The night sky's lights besides the aurora and the airglow, as plain
//! functions on plain data: the stars of the Hipparcos catalogue to V = 8.5
//! ([`catalogue`]), a star's temperature and irradiance from its B-V and V
//! ([`star_colour`]), a star's light through the air per channel
//! ([`star_extinction`]), the Moon's light and the sky it brightens
//! ([`moonlight`]), and the broadband light between the airglow's lines:
//! zodiacal light, integrated starlight, the airglow continuum
//! ([`broadband`]). Brightnesses are in the V band and, converted, in the
//! volume's radiance unit (kR; kR sr for a point source's irradiance), the
//! unit the renderer's stars use.

pub mod broadband;
pub mod catalogue;
pub mod moonlight;
pub mod star_colour;
pub mod star_extinction;
