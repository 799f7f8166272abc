#!/usr/bin/env bash
# Mutation testing of one function of the proof code, with the tests that reach it.
#
#   bench/mutants_named.sh PLACE [NAMES]
#
# PLACE is one of the places below; NAMES, when given, is a file of mutant names (one per line, as
# `cargo mutants --list` prints them) to run instead of every mutant of the function. Runs in place in
# the current checkout (use a scratch copy: cargo-mutants restores each file after its mutant) and
# writes mutants.out/ under bench/out/mutants-PLACE (not in git). Tests: the core crate's unit tests
# and the integration tests named for the place (`TESTS="..."` names others; `TESTS=` runs the unit tests only).
set -euo pipefail
place=${1:?place: hull, spread, reach, eps, slemma, quadric or lines}
names=${2:-}
case $place in
  hull)    file=crates/pluecker/src/triangulation/line/taylor_search.rs
           re='in TaylorOracle<.*>::hull_bound|replace TaylorOracle<.*>::hull_bound ->'
           tests="triangulation_line triangulation_lens_lines" ;;
  spread)  file=crates/pluecker/src/pose/certificate/mod.rs
           re='in Whitening::box_spread|replace Whitening::box_spread ->'
           tests="pose_certificate_bounds pose_certificate_region pose_global pose_lens" ;;
  reach)   file=crates/pluecker/src/pose/certificate/lens.rs
           re='in along_line_reach|replace along_line_reach ->'
           tests="pose_lens pose_certificate_bounds pose_certificate_region" ;;
  eps)     file=crates/pluecker/src/lens_linearisation.rs
           re='in Linearised::epsilon_in$|replace Linearised::epsilon_in ->'
           tests="triangulation_lens triangulation_lens_lines pose_lens" ;;
  slemma)  file=crates/pluecker/src/global/convexity.rs
           re='in Minorant<N>::minimum_subject_to|replace Minorant<N>::minimum_subject_to ->'
           tests="triangulation_quadric" ;;
  quadric) file=crates/pluecker/src/triangulation/quadric/certificate.rs
           re='in convexity_bound$|replace convexity_bound ->'
           tests="triangulation_quadric" ;;
  lines)   file=crates/pluecker/src/pose/certificate/mod.rs
           re='in Problem<.*>::linear_lines_bound|replace Problem<.*>::linear_lines_bound ->|in LineTerm::linear_rest|replace LineTerm::linear_rest ->|in Scaled::second_order_rest|replace Scaled::second_order_rest ->'
           tests="pose_certificate_bounds pose_global" ;;
  *) echo "unknown place $place" >&2; exit 2 ;;
esac
if [ -n "$names" ]; then
  re=$(python3 -c 'import re, sys; print("|".join("^" + re.escape(l.strip()) + "$" for l in open(sys.argv[1]) if l.strip()))' "$names")
fi
extra=()
for t in ${TESTS-$tests}; do extra+=(-C --test -C "$t"); done
# cargo-mutants 27.1 also lists the struct-field deletions of the whole file whatever -F says: they
# are outside the function and are left out of the counts.
cargo mutants --no-config --in-place -f "$file" -F "$re" --profile mutants --test-tool cargo -C --lib "${extra[@]}" \
  --minimum-test-timeout 120 --output "bench/out/mutants-$place"
