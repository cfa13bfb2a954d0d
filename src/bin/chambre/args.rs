//! Value parsers the commands' arguments share: counts of at least 1, pixel tolerances,
//! spacings and step limits, refused by clap with the flag named and a non-zero exit; the
//! library's named enums (tone maps, samplers, backends, ...) by their names.

use chambre::named::Named;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

/// The parser of a `u32` count given on the command line that must be at least 1 (clap says
/// which flag and why, and exits non-zero).
pub fn positive() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

/// The parser of `--fermat-steps` and `bench fermat --steps`: 1 to
/// `chambre::preview::reflections::kernel::MAX_FERMAT_STEPS`.
pub fn fermat_steps() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32)
        .range(1..=i64::from(chambre::preview::reflections::kernel::MAX_FERMAT_STEPS))
}

/// A spacing of copies in mesh widths: at least 1, so that they do not overlap.
pub fn at_least_one_width(text: &str) -> std::result::Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 1.0 => Ok(v),
        Ok(_) => Err("must be a finite number of widths, at least 1".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// A count given on the command line that must be at least 1 (a size, a number of runs or
/// copies): 0 would measure nothing and report NaN, or be taken silently as 1.
pub fn at_least_one(text: &str) -> std::result::Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

/// The parser of `--tessellation-tolerance`: a finite number of pixels above 0 (0 would ask
/// every curved shape for its finest grid, and say each strays too far).
pub fn tolerance_px(text: &str) -> std::result::Result<f64, String> {
    match text.parse::<f64>() {
        Ok(px) if px.is_finite() && px > 0.0 => Ok(px),
        Ok(_) => Err("must be a number of pixels above 0".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// The parser of a flag that takes the names of a library enum ([`Named`]): `--help` lists
/// each name with its doc comment's summary, and clap refuses any other with the names listed.
pub fn named<T: Named + Send + Sync>() -> impl TypedValueParser<Value = T> {
    let values = T::VALUES
        .iter()
        .map(|v| PossibleValue::new(v.name).help(v.summary()));
    PossibleValuesParser::new(values)
        .try_map(|name| T::from_name(&name).ok_or("a name the possible values hold"))
}
