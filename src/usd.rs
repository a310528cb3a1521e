//! usd (to be written)
