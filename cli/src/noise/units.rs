//! The IEEE Std 952-1997 units of the text output: a gyro in deg/s or rad/s, an accelerometer
//! in g or m/s^2. The JSON keeps the column's own unit `u` (`N` in u/sqrt(Hz), `K` in
//! u/s/sqrt(Hz), `B` in u).

use crate::input::units::{G, Quantity, Unit};

/// What the column measures, by its unit.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// A rate gyro: the angle unit (deg or rad) and the factor to that angle per second.
    Gyro(&'static str, f64),
    /// An accelerometer, with the factor to m/s^2.
    Accelerometer(f64),
    /// Any other unit: a label.
    Other,
}

/// The column's unit and its conversions.
pub struct Units {
    /// The unit as given.
    pub name: String,
    kind: Kind,
}

impl Units {
    /// The unit named `name` (an angular rate or an acceleration of
    /// [`Unit`](crate::input::units::Unit); anything else is a label).
    pub fn of(name: &str) -> Self {
        let kind = match Unit::parse(name) {
            Some(u) if u.name == "rad/s" => Kind::Gyro("rad", 1.0),
            Some(u) if u.quantity == Quantity::AngularRate => {
                Kind::Gyro("deg", u.to_si * 180.0 / std::f64::consts::PI)
            }
            Some(u) => Kind::Accelerometer(u.to_si),
            None => Kind::Other,
        };
        Self {
            name: name.to_string(),
            kind,
        }
    }

    /// The unit of `N`, u/sqrt(Hz).
    pub fn psd_root(&self) -> String {
        format!("{}/sqrt(Hz)", self.name)
    }

    /// `N` as angle random walk in deg/sqrt(h) (a gyro; in rad/sqrt(h) first for a gyro in
    /// rad/s), or velocity random walk in m/s/sqrt(h) (an accelerometer): ` = ...`, or nothing.
    pub fn arw(&self, n: f64) -> String {
        match self.kind {
            Kind::Gyro(angle, f) => Self::angles(angle, 60.0 * n * f, "/sqrt(h)"),
            Kind::Accelerometer(to_si) => format!(" = {} m/s/sqrt(h)", short(60.0 * n * to_si)),
            Kind::Other => String::new(),
        }
    }

    /// `K` of a gyro in deg/h/sqrt(h) (`216000 K`; in rad/h/sqrt(h) first for a gyro in
    /// rad/s), of an accelerometer in m/s/h/sqrt(h): ` = ...`, or nothing.
    pub fn rrw(&self, k: f64) -> String {
        match self.kind {
            Kind::Gyro(angle, f) => Self::angles(angle, 3600.0 * 60.0 * k * f, "/h/sqrt(h)"),
            Kind::Accelerometer(to_si) => {
                format!(" = {} m/s/h/sqrt(h)", short(3600.0 * 60.0 * k * to_si))
            }
            Kind::Other => String::new(),
        }
    }

    /// `B` of a gyro in deg/h (in rad/h first for a gyro in rad/s), of an accelerometer in
    /// micro-g: ` = ...`, or nothing.
    pub fn bias(&self, b: f64) -> String {
        match self.kind {
            Kind::Gyro(angle, f) => Self::angles(angle, 3600.0 * b * f, "/h"),
            Kind::Accelerometer(to_si) => format!(" = {} ug", short(1e6 * b * to_si / G)),
            Kind::Other => String::new(),
        }
    }

    /// ` = v angle<per>`, and ` = v deg<per>` after it when `angle` is rad (datasheets print
    /// degrees).
    fn angles(angle: &str, v: f64, per: &str) -> String {
        let mut s = format!(" = {} {angle}{per}", short(v));
        if angle == "rad" {
            s += &format!(" = {} deg{per}", short(v.to_degrees()));
        }
        s
    }
}

/// `v` to 4 significant digits.
fn short(v: f64) -> String {
    format!("{v:.4e}")
        .parse::<f64>()
        .map_or_else(|_| v.to_string(), |r| r.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gyro_and_accelerometer_conversions() {
        let deg = Units::of("deg/s");
        // 1 deg/s/sqrt(Hz) = 1 deg/sqrt(s) = 60 deg/sqrt(h).
        assert_eq!(deg.arw(0.5), " = 30 deg/sqrt(h)");
        assert_eq!(deg.bias(1e-3), " = 3.6 deg/h");
        assert_eq!(deg.rrw(1e-5), " = 2.16 deg/h/sqrt(h)");
        let g = Units::of("g");
        assert_eq!(g.bias(2e-5), " = 20 ug");
        assert_eq!(g.arw(1e-4), " = 0.05884 m/s/sqrt(h)");
        assert_eq!(Units::of("m/s^2").bias(G * 1e-6), " = 1 ug");
        assert_eq!(Units::of("counts").arw(1.0), "");
        // 3600 deg/h = 1 deg/s.
        assert_eq!(Units::of("deg/h").bias(3600.0 * 1e-3), " = 3.6 deg/h");
        // A gyro in rad/s: radians, then the degrees datasheets print.
        let rad = Units::of("rad/s");
        assert_eq!(rad.arw(1e-3), " = 0.06 rad/sqrt(h) = 3.4377 deg/sqrt(h)");
        assert_eq!(
            rad.rrw(1e-5),
            " = 2.16 rad/h/sqrt(h) = 123.76 deg/h/sqrt(h)"
        );
        // An accelerometer's K: 1 m/s^2/sqrt(s) = 216000 m/s/h/sqrt(h).
        assert_eq!(Units::of("m/s^2").rrw(1e-5), " = 2.16 m/s/h/sqrt(h)");
    }
}
