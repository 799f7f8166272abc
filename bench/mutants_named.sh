#!/usr/bin/env bash
# Mutation testing of one function of the proof code, with the tests that reach it.
#
#   bench/mutants_named.sh PLACE [NAMES]
#
# PLACE is one of the places below; NAMES, when given, is a file of mutant names (one per line, as
# `cargo mutants --list` prints them) to run instead of every mutant of the function. Runs in place in
# the current checkout (use a scratch copy: cargo-mutants restores each file after its mutant) and
# writes mutants.out/ under bench/out/mutants-PLACE (not in git). Tests: the core crate's unit tests and
# its one integration-test binary `it` (`TESTS=` runs the unit tests only).
set -euo pipefail
place=${1:?place: hull, spread, reach, eps, slemma, quadric or lines}
names=${2:-}
case $place in
  hull)    files=(crates/pluecker/src/triangulation/line/taylor_search.rs)
           re='in TaylorOracle<.*>::hull_bound|replace TaylorOracle<.*>::hull_bound ->' ;;
  spread)  files=(crates/pluecker/src/pose/certificate/local_bound.rs)
           re='in Whitening::box_spread|replace Whitening::box_spread ->' ;;
  reach)   files=(crates/pluecker/src/pose/certificate/lens.rs)
           re='in along_line_reach|replace along_line_reach ->' ;;
  eps)     files=(crates/pluecker/src/camera/linearisation.rs)
           re='in LinearisedObservation::epsilon_in$|replace LinearisedObservation::epsilon_in ->' ;;
  slemma)  files=(crates/pluecker/src/global/convexity.rs)
           re='in Minorant<N>::minimum_subject_to|replace Minorant<N>::minimum_subject_to ->' ;;
  quadric) files=(crates/pluecker/src/triangulation/quadric/certificate.rs)
           re='in convexity_bound$|replace convexity_bound ->' ;;
  lines)   files=(crates/pluecker/src/pose/certificate/box_bound.rs crates/pluecker/src/pose/certificate/minorant.rs)
           re='in Problem<.*>::linear_lines_bound|replace Problem<.*>::linear_lines_bound ->|in LineTerm::linear_rest|replace LineTerm::linear_rest ->|in ScaledMinorant::second_order_rest|replace ScaledMinorant::second_order_rest ->' ;;
  *) echo "unknown place $place" >&2; exit 2 ;;
esac
if [ -n "$names" ]; then
  re=$(python3 -c 'import re, sys; print("|".join("^" + re.escape(l.strip()) + "$" for l in open(sys.argv[1]) if l.strip()))' "$names")
fi
extra=()
for t in ${TESTS-it}; do extra+=(-C --test -C "$t"); done
file_args=()
for f in "${files[@]}"; do file_args+=(-f "$f"); done
# cargo-mutants 27.1 also lists the struct-field deletions of the whole file whatever -F says: they
# are outside the function and are left out of the counts.
cargo mutants --no-config --in-place "${file_args[@]}" -F "$re" --profile mutants --test-tool cargo -C --lib "${extra[@]}" \
  --minimum-test-timeout 120 --output "bench/out/mutants-$place"
