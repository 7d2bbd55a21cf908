//! The units a column may be in, and the conversions between them: angular rate in rad/s,
//! deg/s or deg/h; acceleration in m/s^2, g or mg. A unit is spelled as in a header's bracket
//! (`[rad s^-1]`, `[m s^-2]`, EuRoC) or as on the command line (`rad/s`, `m/s^2`).

/// Standard gravity, m/s^2.
pub const G: f64 = 9.806_65;

/// What a unit measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Angular rate (a gyro).
    AngularRate,
    /// Specific force (an accelerometer).
    Acceleration,
}

/// A known unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    /// Its canonical name (`rad/s`, `deg/s`, `deg/h`, `m/s^2`, `g`, `mg`).
    pub name: &'static str,
    /// What it measures.
    pub quantity: Quantity,
    /// One of it in SI units (rad/s or m/s^2).
    pub to_si: f64,
}

/// The known units.
const UNITS: [(&[&str], Unit); 6] = [
    (
        &["rad/s", "rads^-1", "rad/sec", "rad*s^-1"],
        unit("rad/s", Quantity::AngularRate, 1.0),
    ),
    (
        &["deg/s", "degs^-1", "dps", "\u{b0}/s", "deg/sec"],
        unit("deg/s", Quantity::AngularRate, std::f64::consts::PI / 180.0),
    ),
    (
        &["deg/h", "degh^-1", "deg/hr", "dph", "\u{b0}/h"],
        unit(
            "deg/h",
            Quantity::AngularRate,
            std::f64::consts::PI / 180.0 / 3600.0,
        ),
    ),
    (
        &["m/s^2", "ms^-2", "m/s2", "m/s/s", "m*s^-2"],
        unit("m/s^2", Quantity::Acceleration, 1.0),
    ),
    (&["g"], unit("g", Quantity::Acceleration, G)),
    (&["mg"], unit("mg", Quantity::Acceleration, G * 1e-3)),
];

const fn unit(name: &'static str, quantity: Quantity, to_si: f64) -> Unit {
    Unit {
        name,
        quantity,
        to_si,
    }
}

impl Unit {
    /// The unit spelled `name` (spaces and case ignored),
    /// or `None` for a unit not known here.
    pub fn parse(name: &str) -> Option<Self> {
        let exact: String = name.chars().filter(|c| !c.is_whitespace()).collect();
        // g and mg only as written: G and mG are gauss.
        if exact.eq_ignore_ascii_case("g") || exact.eq_ignore_ascii_case("mg") {
            return UNITS[4..]
                .iter()
                .find(|(spellings, _)| spellings.contains(&exact.as_str()))
                .map(|(_, u)| *u);
        }
        let key = exact.to_lowercase();
        UNITS
            .iter()
            .find(|(spellings, _)| spellings.contains(&key.as_str()))
            .map(|(_, u)| *u)
    }

    /// The SI unit of what it measures.
    pub fn si(self) -> Self {
        match self.quantity {
            Quantity::AngularRate => UNITS[0].1,
            Quantity::Acceleration => UNITS[3].1,
        }
    }

    /// The factor from this unit to `to`; an error when they measure different things.
    pub fn factor_to(self, to: Self) -> Result<f64, String> {
        if self.quantity != to.quantity {
            return Err(format!(
                "cannot convert {} to {}: one is an angular rate, the other an acceleration",
                self.name, to.name
            ));
        }
        Ok(self.to_si / to.to_si)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_and_factors() {
        let rad = Unit::parse("rad s^-1").unwrap();
        assert_eq!(rad.name, "rad/s");
        assert_eq!(Unit::parse("m s^-2").unwrap().name, "m/s^2");
        let deg = Unit::parse("deg/s").unwrap();
        assert!((rad.factor_to(deg).unwrap() - 180.0 / std::f64::consts::PI).abs() < 1e-12);
        let dph = Unit::parse("deg/h").unwrap();
        assert!((deg.factor_to(dph).unwrap() - 3600.0).abs() < 1e-9);
        assert_eq!(
            Unit::parse("g")
                .unwrap()
                .factor_to(Unit::parse("m/s^2").unwrap()),
            Ok(G)
        );
        assert!(rad.factor_to(Unit::parse("g").unwrap()).is_err());
        assert_eq!(Unit::parse("counts"), None);
        assert_eq!(Unit::parse("mG"), None);
        assert_eq!(Unit::parse("G"), None);
    }
}
