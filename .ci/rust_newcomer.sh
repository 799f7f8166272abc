#!/usr/bin/env bash
# The README's Rust path, as a newcomer takes it: a fresh `cargo new` project in a temporary folder, the
# crate added with the README's own `cargo add pluecker --path ...` command (its placeholder path replaced
# by this checkout's), the README's ```rust snippet pasted verbatim as src/main.rs, then built and run.
# A snippet that does not compile as written fails here, and so does a README without one.
#
# Two things differ from a newcomer's machine, to keep it cheap and offline: the project starts from this
# checkout's Cargo.lock (the dependency versions the tests ran with, already in ~/.cargo/registry; cargo
# drops the entries it does not need), and it builds into this checkout's target/ with the workspace's
# release settings, so the dependencies `cargo test --release` built are reused.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
readme="$root/README.md"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmd=$(grep -o '`cargo add pluecker --path [^`]*`' "$readme" | head -n 1 | tr -d '`')
[ -n "$cmd" ] || { echo "$readme: no \`cargo add pluecker --path ...\` to follow" >&2; exit 1; }
path=${cmd#cargo add pluecker --path }
cmd=${cmd/"$path"/"$root/crates/pluecker"}

cd "$work"
cargo new --quiet --vcs none newcomer
cd newcomer
cp "$root/Cargo.lock" Cargo.lock
echo "+ $cmd"
$cmd
python3 - "$readme" > src/main.rs <<'PY'
import re, sys
snippets = re.findall(r"```rust\n(.*?)```", open(sys.argv[1], encoding="utf-8").read(), flags=re.S)
if len(snippets) != 1:
    sys.exit(f"{sys.argv[1]}: expected one ```rust snippet (a whole src/main.rs), found {len(snippets)}")
sys.stdout.write(snippets[0])
PY
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
export CARGO_PROFILE_RELEASE_LTO=thin CARGO_PROFILE_RELEASE_CODEGEN_UNITS=4  # the workspace's [profile.release]
cargo run --release
