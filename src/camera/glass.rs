//! Glass dispersion: a medium's refractive index against wavelength, by Sellmeier's equation
//!
//! n(λ)² = 1 + Σᵢ Bᵢ λ² / (λ² − Cᵢ)   (λ in µm, Cᵢ in µm², three terms),
//!
//! the form glass catalogues (Schott, Ohara, Hoya) publish. A prescription gives either the three
//! pairs (Bᵢ, Cᵢ) per glass, or its index and Abbe number at a reference line, from which a
//! one-term Sellmeier glass is fitted ([`Glass::from_abbe`]); a glass with neither keeps its index
//! at every wavelength. Model and equations: `docs/lens.md` ("Spectral mode").

/// Wavelengths (nm) of the Fraunhofer lines dispersion is quoted at: helium d, mercury e,
/// hydrogen F and C, cadmium F' and C'.
pub const LINE_D_NM: f64 = 587.5618;
/// Mercury e.
pub const LINE_E_NM: f64 = 546.0740;
/// Hydrogen F.
pub const LINE_F_NM: f64 = 486.1327;
/// Hydrogen C.
pub const LINE_C_NM: f64 = 656.2725;
/// Cadmium F'.
pub const LINE_F_PRIME_NM: f64 = 479.9914;
/// Cadmium C'.
pub const LINE_C_PRIME_NM: f64 = 643.8469;

/// The line a prescription's indices (and Abbe numbers) are given at: d, with
/// ν_d = (n_d − 1) / (n_F − n_C), or e, with ν_e = (n_e − 1) / (n_F' − n_C').
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ReferenceLine {
    /// Helium d, 587.56 nm: most catalogues and patents.
    #[default]
    D,
    /// Mercury e, 546.07 nm: many German patents (the Sironar-N's among them).
    E,
}

impl ReferenceLine {
    /// The line named `d` or `e` (either case).
    pub fn parse(word: &str) -> Option<ReferenceLine> {
        match word {
            "d" | "D" => Some(ReferenceLine::D),
            "e" | "E" => Some(ReferenceLine::E),
            _ => None,
        }
    }

    /// Its wavelength (nm).
    pub fn nm(self) -> f64 {
        match self {
            ReferenceLine::D => LINE_D_NM,
            ReferenceLine::E => LINE_E_NM,
        }
    }

    /// The short and long lines its Abbe number spans (nm).
    pub fn abbe_span(self) -> (f64, f64) {
        match self {
            ReferenceLine::D => (LINE_F_NM, LINE_C_NM),
            ReferenceLine::E => (LINE_F_PRIME_NM, LINE_C_PRIME_NM),
        }
    }
}

/// The shortest and longest wavelengths (nm) a glass must stay finite and transparent between:
/// the spectral mode's range (`layout::SPECTRAL_MIN_NM`, `SPECTRAL_MAX_NM`).
const SHORTEST_NM: f64 = crate::layout::SPECTRAL_MIN_NM as f64;
/// The longest.
const LONGEST_NM: f64 = crate::layout::SPECTRAL_MAX_NM as f64;

/// A medium's index against wavelength: Sellmeier's three terms (Bᵢ, Cᵢ), C in µm².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    /// The terms (B, C).
    pub terms: [[f64; 2]; 3],
}

impl Glass {
    /// Air (index 1 at every wavelength: its dispersion, 3e-6 across the visible, is left out).
    pub const AIR: Glass = Glass {
        terms: [[0.0; 2]; 3],
    };

    /// A medium of index `index` at every wavelength (B₁ = n² − 1, C₁ = 0).
    pub fn constant(index: f64) -> Glass {
        Glass {
            terms: [[index * index - 1.0, 0.0], [0.0; 2], [0.0; 2]],
        }
    }

    /// A glass given by its Sellmeier terms; refused when a resonance √Cᵢ lies within a tenth
    /// of the spectral mode's range (in the ultraviolet and infrared is where glass has them).
    pub fn sellmeier(terms: [[f64; 2]; 3]) -> Result<Glass, String> {
        for [b, c] in terms {
            if !(b.is_finite() && c.is_finite()) || b < 0.0 || c < 0.0 {
                return Err(format!(
                    "Sellmeier terms B and C are finite and at least 0, got B = {b}, C = {c}"
                ));
            }
            let resonance = c.sqrt() * 1e3;
            if b > 0.0 && (0.9 * SHORTEST_NM..1.1 * LONGEST_NM).contains(&resonance) {
                return Err(format!(
                    "C = {c} µm² puts a resonance at {resonance:.0} nm, in or next to the range \
                     the spectral mode traces ({SHORTEST_NM}-{LONGEST_NM} nm)"
                ));
            }
        }
        Ok(Glass { terms })
    }

    /// The one-term Sellmeier glass n² = 1 + B λ² / (λ² − C) that has index `index` at `line`
    /// and Abbe number `abbe` there: B = (n² − 1)(1 − C / λ_ref²) keeps the index, and C (a
    /// resonance in the ultraviolet) is found by bisection so that n(short) − n(long) =
    /// (index − 1) / abbe. Refused when the dispersion asks for a resonance inside the visible
    /// range.
    pub fn from_abbe(index: f64, abbe: f64, line: ReferenceLine) -> Result<Glass, String> {
        if !(index > 1.0 && index.is_finite()) {
            return Err(format!(
                "{index}: an Abbe number needs glass (an index above 1)"
            ));
        }
        if !(abbe > 0.0 && abbe.is_finite()) {
            return Err(format!("{abbe}: an Abbe number is positive"));
        }
        let reference = line.nm() * 1e-3;
        let (short, long) = line.abbe_span();
        let spread = (index - 1.0) / abbe;
        let with = |c: f64| Glass {
            terms: [
                [
                    (index * index - 1.0) * (1.0 - c / (reference * reference)),
                    c,
                ],
                [0.0; 2],
                [0.0; 2],
            ],
        };
        let spread_of = |c: f64| {
            let glass = with(c);
            glass.index(short) - glass.index(long)
        };
        // The spread grows from 0 at C = 0 without bound as C nears the short line's λ²; the
        // resonance is kept a tenth below the range's shortest wavelength, where the index
        // is still that of glass.
        let limit = (0.9 * SHORTEST_NM * 1e-3).powi(2);
        if spread_of(limit) <= spread {
            return Err(format!(
                "ν = {abbe} at n = {index}: too dispersive for a one-term Sellmeier glass \
                 transparent from {SHORTEST_NM} nm (give the glass's Sellmeier terms instead)"
            ));
        }
        let (mut lo, mut hi) = (0.0, limit);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if spread_of(mid) < spread {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(with(0.5 * (lo + hi)))
    }

    /// The index at `nm` nanometres.
    pub fn index(&self, nm: f64) -> f64 {
        let l2 = (nm * 1e-3) * (nm * 1e-3);
        let sum: f64 = self.terms.iter().map(|[b, c]| b * l2 / (l2 - c)).sum();
        (1.0 + sum).sqrt()
    }

    /// Whether its index is the same at every wavelength.
    pub fn is_constant(&self) -> bool {
        self.terms.iter().all(|[b, c]| *b == 0.0 || *c == 0.0)
    }

    /// The terms as the kernels read them (f32 pairs, `LensSystem::kernel_table`).
    pub fn kernel_terms(&self) -> [[f32; 2]; 3] {
        self.terms.map(|[b, c]| [b as f32, c as f32])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Schott's N-BK7 (catalogue 2017): n_d 1.51680, ν_d 64.17.
    const N_BK7: [[f64; 2]; 3] = [
        [1.03961212, 0.00600069867],
        [0.231792344, 0.0200179144],
        [1.01046945, 103.560653],
    ];

    #[test]
    fn schott_n_bk7_has_its_catalogue_index_and_abbe_number() {
        let glass = Glass::sellmeier(N_BK7).unwrap();
        let n_d = glass.index(LINE_D_NM);
        assert!((n_d - 1.51680).abs() < 1e-5, "{n_d}");
        let abbe = (n_d - 1.0) / (glass.index(LINE_F_NM) - glass.index(LINE_C_NM));
        assert!((abbe - 64.17).abs() < 0.01, "{abbe}");
    }

    /// The one-term fit keeps the index at its line exactly and the Abbe number to 1e-9, for
    /// crowns and flints at both lines.
    #[test]
    fn an_abbe_fit_keeps_the_index_and_the_abbe_number() {
        for line in [ReferenceLine::D, ReferenceLine::E] {
            for (n, v) in [
                (1.5168, 64.17),
                (1.6055, 60.35),
                (1.805, 25.4),
                (1.9229, 20.9),
            ] {
                let glass = Glass::from_abbe(n, v, line).unwrap();
                let (short, long) = line.abbe_span();
                let fitted =
                    (glass.index(line.nm()) - 1.0) / (glass.index(short) - glass.index(long));
                assert!((glass.index(line.nm()) - n).abs() < 1e-12, "{line:?} {n}");
                assert!((fitted - v).abs() < 1e-9 * v, "{line:?} {n} {v}: {fitted}");
                // Normal dispersion: the index falls with wavelength across the range.
                assert!(
                    glass.index(380.0) > glass.index(500.0)
                        && glass.index(600.0) > glass.index(740.0)
                );
            }
        }
    }

    /// Near N-BK7's own data, the one-term fit stays within 1e-3 of the catalogue's three terms
    /// across 380-740 nm: the visible is far from the glass's resonances.
    #[test]
    fn an_abbe_fit_follows_a_catalogue_glass_across_the_visible() {
        let catalogue = Glass::sellmeier(N_BK7).unwrap();
        let (n_d, f, c) = (
            catalogue.index(LINE_D_NM),
            catalogue.index(LINE_F_NM),
            catalogue.index(LINE_C_NM),
        );
        let fitted = Glass::from_abbe(n_d, (n_d - 1.0) / (f - c), ReferenceLine::D).unwrap();
        for nm in (380..=740).step_by(20) {
            let gap = (fitted.index(nm as f64) - catalogue.index(nm as f64)).abs();
            assert!(gap < 1e-3, "{nm} nm: {gap}");
        }
    }

    #[test]
    fn impossible_glasses_are_refused() {
        assert!(Glass::from_abbe(1.0, 50.0, ReferenceLine::D).is_err());
        assert!(Glass::from_abbe(1.5, 0.0, ReferenceLine::D).is_err());
        assert!(Glass::from_abbe(1.5, f64::NAN, ReferenceLine::D).is_err());
        // A dispersion no glass transparent down to 380 nm has.
        assert!(Glass::from_abbe(1.5, 2.0, ReferenceLine::D).is_err());
        assert!(Glass::sellmeier([[1.0, 0.2], [0.0; 2], [0.0; 2]]).is_err());
        assert!(Glass::sellmeier([[1.0, 0.6], [0.0; 2], [0.0; 2]]).is_err());
        assert!(Glass::sellmeier([[-1.0, 0.01], [0.0; 2], [0.0; 2]]).is_err());
        assert!(Glass::constant(1.5).is_constant() && Glass::AIR.is_constant());
        assert!((Glass::constant(1.7).index(400.0) - 1.7).abs() < 1e-15);
    }
}
