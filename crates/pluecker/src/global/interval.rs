//! Closed intervals and the interval arithmetic of the Taylor bounds ([`super::taylor_bound`]).
//!
//! Every operation returns an interval that contains every value of the operation over its
//! arguments' intervals (the inclusion property), so a bound computed from them holds for every
//! point of a box. Rounding is not directed: the callers widen their final bounds by a relative
//! margin ([`super::taylor_bound::ROUNDING_MARGIN`]) far above the rounding error of these few
//! operations. A division by an interval containing 0 gives the whole line `[−∞, ∞]`.

/// A closed interval `[lo, hi]` (`lo ≤ hi`; infinite ends allowed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Interval {
    /// `[lo, hi]`.
    pub fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi }
    }

    /// The point interval `[x, x]`.
    pub fn point(x: f64) -> Interval {
        Interval { lo: x, hi: x }
    }

    /// `[c − r, c + r]` (`r ≥ 0`).
    pub fn centred(c: f64, r: f64) -> Interval {
        Interval { lo: c - r, hi: c + r }
    }

    /// The whole real line.
    pub fn entire() -> Interval {
        Interval {
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        }
    }

    /// `{c a}`.
    pub fn scale(self, c: f64) -> Interval {
        if c >= 0.0 {
            Interval {
                lo: c * self.lo,
                hi: c * self.hi,
            }
        } else {
            Interval {
                lo: c * self.hi,
                hi: c * self.lo,
            }
        }
    }

    /// `{a²}`: tighter than `a · a`, never negative.
    pub fn sqr(self) -> Interval {
        let (a, b) = (self.lo * self.lo, self.hi * self.hi);
        if self.lo >= 0.0 || self.hi <= 0.0 {
            Interval::new(a.min(b), a.max(b))
        } else {
            Interval::new(0.0, a.max(b))
        }
    }

    /// The intersection with `other` (which must overlap: both contain the same true value).
    pub fn meet(self, other: Interval) -> Interval {
        Interval {
            lo: self.lo.max(other.lo),
            hi: self.hi.min(other.hi),
        }
    }

    /// The mignitude `min |a|`: 0 when the interval contains 0.
    pub fn mig(self) -> f64 {
        if self.lo > 0.0 {
            self.lo
        } else if self.hi < 0.0 {
            -self.hi
        } else {
            0.0
        }
    }

    /// The magnitude `max |a|`.
    pub fn mag(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    /// True when `0 ∈ [lo, hi]` (or an end is NaN: nothing is excluded).
    pub fn contains_zero(self) -> bool {
        !(self.lo > 0.0 || self.hi < 0.0)
    }
}

// The four operations are the std operators (`a + b`, `a.add(b)` with the trait in scope).
impl std::ops::Add for Interval {
    type Output = Interval;

    /// `{a + b}`.
    fn add(self, other: Interval) -> Interval {
        Interval {
            lo: self.lo + other.lo,
            hi: self.hi + other.hi,
        }
    }
}

impl std::ops::Sub for Interval {
    type Output = Interval;

    /// `{a − b}`.
    fn sub(self, other: Interval) -> Interval {
        Interval {
            lo: self.lo - other.hi,
            hi: self.hi - other.lo,
        }
    }
}

impl std::ops::Mul for Interval {
    type Output = Interval;

    /// `{a b}`: the least and greatest of the four end products (`0 · ∞` counts as 0).
    fn mul(self, other: Interval) -> Interval {
        let p = |a: f64, b: f64| if a == 0.0 || b == 0.0 { 0.0 } else { a * b };
        let c = [
            p(self.lo, other.lo),
            p(self.lo, other.hi),
            p(self.hi, other.lo),
            p(self.hi, other.hi),
        ];
        Interval {
            lo: c.iter().copied().fold(f64::INFINITY, f64::min),
            hi: c.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

impl std::ops::Div for Interval {
    type Output = Interval;

    /// `{a / b}`; the whole line when `b` contains 0.
    fn div(self, other: Interval) -> Interval {
        if other.lo > 0.0 || other.hi < 0.0 {
            self * Interval::new(1.0 / other.hi, 1.0 / other.lo)
        } else {
            Interval::entire()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use std::ops::{Add, Div, Mul, Sub};

    fn random_interval(rng: &mut Rng) -> Interval {
        let (a, b) = (rng.normal() * 3.0, rng.normal() * 3.0);
        Interval::new(a.min(b), a.max(b))
    }

    #[test]
    fn operations_contain_every_value_of_their_arguments() {
        let mut rng = Rng::new(5);
        for _ in 0..2000 {
            let (x, y) = (random_interval(&mut rng), random_interval(&mut rng));
            for _ in 0..20 {
                let a = x.lo + (x.hi - x.lo) * rng.uniform();
                let b = y.lo + (y.hi - y.lo) * rng.uniform();
                let inside = |i: Interval, v: f64| i.lo <= v && v <= i.hi;
                assert!(inside(x.add(y), a + b));
                assert!(inside(x.sub(y), a - b));
                assert!(inside(x.mul(y), a * b));
                assert!(inside(x.sqr(), a * a));
                assert!(inside(x.scale(-1.7), -1.7 * a));
                assert!(inside(x.div(y), a / b) || (y.lo <= 0.0 && y.hi >= 0.0));
                assert!(x.mig() <= a.abs() && a.abs() <= x.mag());
            }
        }
        assert!(Interval::new(-1.0, 2.0).div(Interval::new(-1.0, 1.0)).lo == f64::NEG_INFINITY);
        assert_eq!(Interval::new(-2.0, 1.0).sqr(), Interval::new(0.0, 4.0));
        assert_eq!(Interval::entire().mul(Interval::point(0.0)), Interval::point(0.0));
    }
}
