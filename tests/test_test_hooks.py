"""The extension's test hooks are in the development build and out of the wheel.

The hooks (``_panic_for_tests``, ``_on_poll_for_tests``, ...) are compiled in only with the cargo feature
``test-hooks`` of crates/pluecker-py: ``make develop`` turns it on, ``pip install .`` and ``maturin build``
(pyproject.toml) do not. The tests that call a hook go through ``conftest.hooks``, which fails the test
with how to build the hooks in when they are missing; this file says it once for the whole run."""

from __future__ import annotations

import re
from pathlib import Path

from conftest import TEST_HOOKS, missing_hook_message

import pluecker

ROOT = Path(__file__).resolve().parents[1]


def test_the_tested_build_has_every_test_hook():
    missing = [name for name in TEST_HOOKS if not hasattr(pluecker._core, name)]
    assert not missing, "\n".join(missing_hook_message(name) for name in missing)


def test_the_wheel_is_built_without_the_test_hooks():
    """The wheel's build (pyproject.toml's ``[tool.maturin]``) and the crate's default features leave the
    feature out, and the Makefile's development build is the one that turns it on."""
    maturin = re.search(r"^\[tool\.maturin\]\n(.*?)(?=^\[)", (ROOT / "pyproject.toml").read_text(), re.S | re.M)
    assert maturin and "test-hooks" not in maturin.group(1)
    manifest = (ROOT / "crates" / "pluecker-py" / "Cargo.toml").read_text()
    default = re.search(r"^default = \[(.*?)\]", manifest, re.M)
    assert default and "test-hooks" not in default.group(1)
    assert re.search(r"^test-hooks = \[\]", manifest, re.M)
    assert "maturin develop --release --features test-hooks" in (ROOT / "Makefile").read_text()
