"""Writes the properties of ``_core.pyi`` from the extension's own tables.

Every result and options class of ``pluecker._core`` declares each property once, in Rust
(``crates/pluecker-py/src/properties.rs``), and publishes it as ``__fields__``: ``(name, type, doc)``.
In ``_core.pyi`` each such class holds one generated block::

    # fields of PoseResult (generated: python -m pluecker._stubgen)
    R: NDArray[np.float64]
    \"\"\"Rotation, ...\"\"\"
    # end of fields

which this module rewrites from ``__fields__``; for an options class the block also holds its
``__init__`` with every default, read from a default-constructed instance (that is, from the Rust
``Default``). ``python -m pluecker._stubgen`` rewrites the file; ``--check`` only says whether it
is up to date (``tests/test_stubs.py`` runs the check).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from . import _core

STUB = Path(__file__).with_name("_core.pyi")
BLOCK = re.compile(
    r"(?P<indent>[ ]*)# fields of (?P<cls>\w+) \(generated: python -m pluecker._stubgen\)\n"
    r".*?"
    r"(?P=indent)# end of fields\n",
    re.S,
)


def _own_fields(cls: type) -> list[tuple[str, str, str]]:
    """The ``__fields__`` a class declares itself (a subclass inherits its base's attribute)."""
    fields = cls.__dict__.get("__fields__")
    return list(fields) if fields is not None else []


def _docstring(doc: str, indent: str) -> list[str]:
    lines = doc.strip().splitlines() or [""]
    if len(lines) == 1:
        return [f'{indent}"""{lines[0]}"""']
    return [f'{indent}"""{lines[0]}'] + [f"{indent}{line}" if line else "" for line in lines[1:]] + [f'{indent}"""']


def _default(value: object) -> str:
    """A default as the stub writes it: nested options (a dict in ``to_dict``) as ``...``."""
    return "..." if isinstance(value, dict) else repr(value)


def _is_options(cls: type) -> bool:
    return cls.__name__.endswith("Options")


def block(cls_name: str, indent: str = "    ") -> str:
    """The generated block of class ``cls_name``."""
    cls = getattr(_core, cls_name)
    fields = _own_fields(cls)
    out = [f"{indent}# fields of {cls_name} (generated: python -m pluecker._stubgen)"]
    if _is_options(cls):
        defaults = cls().to_dict()
        params = ", ".join(f"{name}: {kind} = {_default(defaults[name])}" for name, kind, _ in fields)
        out.append(f'{indent}def __new__(cls, *, {params}) -> "{cls_name}": ...')
    out.append(f"{indent}__fields__: ClassVar[List[Tuple[str, str, str]]]")
    for name, kind, doc in fields:
        out.append(f"{indent}{name}: {kind}")
        out.extend(_docstring(doc, indent))
    out.append(f"{indent}# end of fields")
    return "\n".join(out) + "\n"


# A class that Python code cannot subclass (PyO3's default) is ``@final`` in the stub.
_BASETYPE = 1 << 10  # Py_TPFLAGS_BASETYPE
CLASS = re.compile(r"^(?:@final\n)?class (?P<cls>\w+)\b", re.M)


def _header(cls_name: str) -> str:
    cls = getattr(_core, cls_name, None)
    final = isinstance(cls, type) and not cls.__flags__ & _BASETYPE
    return f"{'@final' + chr(10) if final else ''}class {cls_name}"


def render(text: str) -> str:
    """``text`` (a ``_core.pyi``) with every generated block rewritten and every class's ``@final`` set."""
    text = BLOCK.sub(lambda m: block(m["cls"], m["indent"]), text)
    return CLASS.sub(lambda m: _header(m["cls"]), text)


def classes_with_fields() -> list[str]:
    """Every class of the extension that declares properties in a table."""
    return sorted(n for n, v in vars(_core).items() if isinstance(v, type) and _own_fields(v))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m pluecker._stubgen", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if _core.pyi is not up to date")
    args = parser.parse_args(argv)
    text = STUB.read_text(encoding="utf-8")
    new = render(text)
    if args.check:
        if new != text:
            print(f"{STUB} is out of date: run python -m pluecker._stubgen", file=sys.stderr)
            return 1
        return 0
    STUB.write_text(new, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
