//! Global optimisation: branch and bound over boxes, the convex envelopes of Josephson & Kahl 2008
//! (section 4.1) and the adapter to the `clarabel` conic solver.
