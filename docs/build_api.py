"""Generate docs/api.md, the API reference, from the docstrings.

::

    python docs/build_api.py            # write docs/api.md
    python docs/build_api.py --check    # exit 1 if docs/api.md is out of date

The reference covers every name in ``__all__`` of ``bondgraph``, ``diagnosis``, ``prognosis`` and its
subpackages,
the modules the tutorials use beside them (``bondgraph.library``, ``bondgraph.io``, ``bondgraph.drawing``,
``diagnosis.records``, ``prognosis.metrics``), what a generated document says of its origin
(``bondgraph.provenance``), the rules of a model's names and domains (``bondgraph.names``,
``bondgraph.domains``), ``bgphm.cli.main``, the public functions of
``bgphm.plotting`` and the fleet API of ``bgphm.fleet``.  Names are grouped by the module that defines
them, in source order; a class is followed by its public methods and properties.  Signatures come from
:func:`inspect.signature`, docstrings are taken as they are (numpy style) and rendered as markdown: sections become bold
headings, parameter lists become bullet lists, ``>>>`` examples become ```` ```pycon ```` blocks.

The output depends only on the code and the docstrings (no dates, no memory addresses), so
``tests/cases/test_docs.py`` can compare it with the committed file.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTPUT = ROOT / "docs" / "api.md"

#: (package, title, extra modules documented in full: every public name they define, or their __all__).
PACKAGES = [
    ("bondgraph", "model, causality, equations, simulation",
     ["bondgraph.library", "bondgraph.io", "bondgraph.drawing", "bondgraph.names", "bondgraph.domains",
      "bondgraph.units", "bondgraph.dimensions", "bondgraph.provenance"]),
    ("diagnosis", "ARRs, intervals, thresholds, signatures, detection", ["diagnosis.records"]),
    ("diagnosis.intervals", "outward-rounded interval arithmetic and the sympy-to-interval compiler", []),
    ("prognosis", "degradation laws, observation model, particle filter, RUL, metrics, health monitoring",
     ["prognosis.metrics", "prognosis.weighted", "prognosis.ranking", "prognosis.seeds"]),
    ("prognosis.statespace", "discrete models, Kalman filters, bootstrap filter, consistency, look-ahead, ROS-ELM", []),
    ("prognosis.identification", "linear Gaussian models by EM, fault trend, posterior predictive", []),
    ("prognosis.lifecontrol", "energy-driven deterioration, Chebyshev bounds, Monte Carlo RUL, RUL control", []),
    ("prognosis.fleet", "many assets in one vectorized filter: streaming, checkpoints, closed-form RUL, tables",
     ["prognosis.random_streams", "prognosis.fleet.closed_form_rul"]),
    ("bgphm", "command line, plots and long runs", ["bgphm.plotting", "bgphm.runs"]),
    ("bgphm.fleet", "fleets on Dask workers, from records to Parquet tables (guide: [docs/fleet.md](fleet.md))", []),
]
#: Modules first in this order within each package (the rest follow alphabetically).
MODULE_ORDER = ["bondgraph.model", "bondgraph.structure", "bondgraph.causality", "bondgraph.equations",
                "bondgraph.simulation", "bondgraph.control", "bondgraph.errors", "bondgraph.library", "bondgraph.io",
                "bondgraph.drawing", "diagnosis.derivation", "diagnosis.deltas", "diagnosis.signatures",
                "diagnosis.detection", "diagnosis.records", "diagnosis.intervals.rounding",
                "diagnosis.intervals.kernels", "diagnosis.intervals.interval", "diagnosis.intervals.functions",
                "diagnosis.intervals.compiler", "prognosis.observation", "prognosis.degradation",
                "prognosis.particle_filter", "prognosis.resample_move", "prognosis.likelihood", "prognosis.wander",
                "prognosis.rul",
                "prognosis.health_monitor", "prognosis.metrics", "prognosis.weighted", "prognosis.ranking", "bgphm.cli",
                "bgphm.plotting", "bgphm.runs"]
#: Names documented for a package that has no useful ``__all__``.
EXPLICIT = {"bgphm": ["bgphm.cli.main"]}

SECTION_TITLES = {"Parameters", "Other Parameters", "Returns", "Yields", "Raises", "Warns", "Attributes",
                  "Examples", "Example", "Notes", "Note", "See Also", "References", "Methods", "Warnings"}
LIST_SECTIONS = {"Parameters", "Other Parameters", "Returns", "Yields", "Raises", "Warns", "Attributes", "Methods"}
WRAP = 96  # signatures longer than this get one parameter per line


# ----------------------------------------------------------------------------------------- collection

@dataclass
class Entry:
    """One documented object: ``qualname`` as users import it, ``module`` where it is defined."""

    qualname: str
    obj: object
    module: str
    line: int
    members: list = field(default_factory=list)


def _source_line(obj) -> int:
    try:
        return inspect.getsourcelines(obj)[1]
    except (OSError, TypeError):
        return 10**9


def _defining_module(obj, fallback: str) -> str:
    return getattr(obj, "__module__", None) or fallback


def _public_names(module) -> list[str]:
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n, v in vars(module).items() if not n.startswith("_") and (inspect.isfunction(v) or
                 inspect.isclass(v)) and getattr(v, "__module__", None) == module.__name__]
    return list(names)


def collect(package: str, extra_modules: list[str]) -> dict[str, list[Entry]]:
    """Module name -> its entries (source order), for a package and its extra modules."""
    sources: list[tuple[str, object]] = []
    if package in EXPLICIT:
        for path in EXPLICIT[package]:
            module_name, name = path.rsplit(".", 1)
            sources.append((path, getattr(importlib.import_module(module_name), name)))
    else:
        module = importlib.import_module(package)
        sources += [(f"{package}.{name}", getattr(module, name)) for name in module.__all__]
    for module_name in extra_modules:
        module = importlib.import_module(module_name)
        sources += [(f"{module_name}.{name}", getattr(module, name)) for name in _public_names(module)]
    seen: set[int] = set()
    modules: dict[str, list[Entry]] = {}
    for qualname, obj in sources:
        if not (inspect.isclass(obj) or callable(obj)) or id(obj) in seen:
            continue  # constants are left out; a name exported twice is documented once
        seen.add(id(obj))
        module = _defining_module(obj, qualname.rsplit(".", 1)[0])
        entry = Entry(qualname, obj, module, _source_line(obj))
        if inspect.isclass(obj):
            entry.members = _members(obj)
        modules.setdefault(module, []).append(entry)
    for entries in modules.values():
        entries.sort(key=lambda e: (e.line, e.qualname))
    rank = {name: i for i, name in enumerate(MODULE_ORDER)}
    return dict(sorted(modules.items(), key=lambda item: (rank.get(item[0], len(rank)), item[0])))


def _members(cls) -> list[tuple[str, object]]:
    """Public methods and properties defined in the class itself (not inherited), in source order."""
    members = []
    for name, value in vars(cls).items():
        if name.startswith("_") and name != "__call__":
            continue
        if isinstance(value, (staticmethod, classmethod)):
            value = value.__func__
        if isinstance(value, property) or inspect.isfunction(value):
            line = _source_line(value.fget if isinstance(value, property) else value)
            members.append((line, name, value))
    return [(name, value) for _, name, value in sorted(members, key=lambda m: (m[0], m[1]))]


# ----------------------------------------------------------------------------------------- signatures

class _Text:
    """An annotation shown as written (``from __future__ import annotations`` keeps them as strings)."""

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


class _Default:
    """A default value shown without a memory address."""

    def __init__(self, value):
        self.value = value

    def __repr__(self) -> str:
        text = repr(self.value)
        if " at 0x" in text:
            return getattr(self.value, "__qualname__", None) or type(self.value).__name__
        return text


def _annotation(value):
    if value is inspect.Parameter.empty:
        return value
    if isinstance(value, str):
        return _Text(value)
    return _Text(inspect.formatannotation(value))


def signature(obj, name: str) -> str | None:
    """``name(params) -> return`` with annotations as written, or None when there is none."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    parameters = []
    for index, p in enumerate(sig.parameters.values()):
        if p.name.startswith("_") or (index == 0 and p.name in ("self", "cls")):
            continue  # private dataclass fields; the instance of a method
        default = p.default if p.default is inspect.Parameter.empty else _Default(p.default)
        parameters.append(p.replace(annotation=_annotation(p.annotation), default=default))
    returns = _annotation(sig.return_annotation) if not inspect.isclass(obj) else inspect.Signature.empty
    sig = sig.replace(parameters=parameters, return_annotation=returns)
    text = f"{name}{sig}"
    if len(text) <= WRAP or not parameters:
        return text
    inner = str(sig.replace(return_annotation=inspect.Signature.empty))[1:-1]
    pieces = _split_top_level(inner)
    tail = "" if returns is inspect.Signature.empty else f" -> {returns!r}"
    return f"{name}(\n" + "".join(f"    {piece},\n" for piece in pieces) + f"){tail}"


def _split_top_level(text: str) -> list[str]:
    """Split a parameter list at the commas outside brackets and quotes."""
    pieces, depth, quote, start = [], 0, None, 0
    for i, ch in enumerate(text):
        if quote:
            if ch == quote and text[i - 1] != "\\":
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            pieces.append(text[start:i].strip())
            start = i + 1
    pieces.append(text[start:].strip())
    return [p for p in pieces if p]


# ----------------------------------------------------------------------------------------- docstrings

ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|exc|obj|const|math|ref|term|doc):`([^`]+)`")
LITERAL = re.compile(r"``(.+?)``", re.S)


def _role(match: re.Match) -> str:
    text = match.group(1)
    label = re.fullmatch(r"(.+?)\s*<(.+)>", text)
    if label:
        return f"`{label.group(1)}`"
    if text.startswith("~"):
        text = text[1:].rsplit(".", 1)[-1]
    return f"`{text}`"


def inline(text: str) -> str:
    """rST inline markup to markdown: ``code`` and :role:`target`."""
    text = ROLE.sub(_role, text)
    return LITERAL.sub(lambda m: f"`{m.group(1)}`", text)


def docstring(obj) -> str:
    """The object's own docstring, cleaned; "" for none (inherited and generated ones are ignored)."""
    doc = obj.__doc__ if not isinstance(obj, property) else obj.fget.__doc__
    if not doc or not isinstance(doc, str):
        return ""
    if inspect.isclass(obj):
        for base in obj.__mro__[1:]:
            if base.__doc__ == doc:
                return ""  # inherited (Exception subclasses without a docstring)
        if doc.startswith(f"{obj.__name__}(") and "\n" not in doc.strip():
            return ""  # the signature dataclasses put in place of a missing docstring
    return inspect.cleandoc(doc)


def split_sections(text: str) -> list[tuple[str | None, list[str]]]:
    """[(title or None for the preamble, lines)] of a numpy-style docstring."""
    lines = text.splitlines()
    sections: list[tuple[str | None, list[str]]] = [(None, [])]
    i = 0
    while i < len(lines):
        title = lines[i].strip()
        underline = lines[i + 1].strip() if i + 1 < len(lines) else ""
        if (title in SECTION_TITLES and re.fullmatch(r"-{3,}", underline)
                and not lines[i].startswith(" ")):
            sections.append((title, []))
            i += 2
            continue
        sections[-1][1].append(lines[i])
        i += 1
    return [(t, body) for t, body in sections if t is not None or any(line.strip() for line in body)]


def _blocks(lines: list[str]) -> list[list[str]]:
    """Split lines into blocks separated by blank lines."""
    blocks, current = [], []
    for line in lines:
        if line.strip():
            current.append(line)
        elif current:
            blocks.append(current)
            current = []
    if current:
        blocks.append(current)
    return blocks


def _dedent(lines: list[str]) -> list[str]:
    indent = min((len(line) - len(line.lstrip()) for line in lines if line.strip()), default=0)
    return [line[indent:] for line in lines]


def _indent(block: list[str]) -> int:
    return min(len(line) - len(line.lstrip()) for line in block if line.strip())


LIST_ITEM = re.compile(r"(\s*)([*+-]|\d+\.)\s+")


def prose(lines: list[str]) -> list[str]:
    """Free text: paragraphs, lists, doctest blocks (```pycon), literal and math blocks (fenced).

    A block indented like the text of the list item above it continues that item; a block after a
    line ending in ``::`` is a literal block; any other indented block (a formula, say) is fenced too.
    """
    out: list[str] = []
    list_indent, literal_after = 0, None  # text column of the open list item; indent of the "::" line
    for block in _blocks(_dedent(lines)):
        indent, first = _indent(block), block[0].lstrip()
        inside = list_indent if list_indent and indent >= list_indent else 0
        pad = " " * inside
        if first.startswith(">>>"):
            out += [pad + "```pycon", *(pad + line for line in _dedent(block)), pad + "```", ""]
        elif first.startswith(".. math::"):
            formula = first[len(".. math::"):].strip()
            body = ([formula] if formula else []) + [line.strip() for line in block[1:]]
            out += [pad + "```math", *(pad + line for line in body), pad + "```", ""]
        elif literal_after is not None and indent > literal_after:
            out += [pad + "```text", *(pad + line for line in _dedent(block)), pad + "```", ""]
        elif indent == 0:
            out += _paragraph(block) + [""]
            items = [LIST_ITEM.match(line) for line in block if not line.startswith(" ")]
            list_indent = items[-1].end() if items and items[-1] else 0
        elif inside and indent == list_indent:
            out += [pad + line for line in _paragraph(_dedent(block))] + [""]
        else:
            out += [pad + "```text", *(pad + line for line in _dedent(block)), pad + "```", ""]
        literal_after = None
        if block[-1].rstrip().endswith("::") and not first.startswith(">>>"):
            literal_after = indent
            last = next(k for k in range(len(out) - 1, -1, -1) if out[k].strip())
            text = out[last].rstrip()
            out[last] = text[:-3].rstrip() if (text.endswith(" ::") or text.strip() == "::") else text[:-1]
    return out


def _paragraph(block: list[str]) -> list[str]:
    """A paragraph or a list; a line followed by more-indented lines is a definition (term + text)."""
    out: list[str] = []
    j = 0
    while j < len(block):
        line = block[j]
        following = []
        k = j + 1
        while k < len(block) and block[k].startswith(" ") and not line.startswith(" "):
            following.append(block[k].strip())
            k += 1
        is_item = LIST_ITEM.match(line)
        if following and not is_item:
            out.append(f"- {line.strip()}: {' '.join(following)}")
        elif following:
            out.append(line.rstrip())
            out += ["  " + text for text in following]
        else:
            out.append(line.rstrip())
        j = k if following else j + 1
    return inline("\n".join(out)).split("\n")  # inline markup may span lines


def _looks_like_prose(line: str, following: str | None) -> bool:
    """A sentence after a list of ``name : type`` entries (not an entry: no colon, no description)."""
    return (" : " not in line and not line.rstrip().endswith(" :") and len(line.split()) >= 5
            and (following is None or not following.startswith(" ")))


def parameter_list(lines: list[str], section: str) -> list[str]:
    """``name : type`` + indented description -> markdown bullets; trailing sentences stay prose."""
    out: list[str] = []
    lines = _dedent(lines)
    items: list[tuple[str | None, list[str]]] = []  # (head, body); head None for a prose paragraph
    blank = False
    for index, line in enumerate(lines):
        following = lines[index + 1] if index + 1 < len(lines) else None
        if not line.strip():
            if items:
                items[-1][1].append(line)
            blank = True
            continue
        if line.startswith(" ") and items:
            items[-1][1].append(line)
        elif items and items[-1][0] is None and not blank:
            items[-1][1].append(line)
        elif items and blank and _looks_like_prose(line, following):
            items.append((None, [line]))
        else:
            items.append((line.strip(), []))
        blank = False
    for head, body in items:
        if head is None:
            out += [""] + prose(body)
            continue
        if " : " in head or head.endswith(" :"):
            name, _, kind = head.partition(" :")
            kind = kind.strip()
            label = f"**`{name.strip()}`**" + (f" ({inline(kind)})" if kind else "")
        elif section in ("Returns", "Yields"):
            label = f"*{inline(head)}*"
        elif section in ("Raises", "Warns") or not re.fullmatch(r"[\w, *]+", head):
            label = f"`{head}`"
        else:
            label = f"**`{head}`**"
        description = prose(body) if any(line.strip() for line in body) else []
        while description and not description[-1].strip():
            description.pop()
        simple = description and all(d.strip() for d in description) and not any(
            d.lstrip().startswith(("```", "- ", "* ")) for d in description)
        if simple:
            out.append(f"- {label}: {' '.join(d.strip() for d in description)}")
        elif description:
            out += [f"- {label}:", ""] + [("    " + d) if d.strip() else "" for d in description]
        else:
            out.append(f"- {label}")
    return out + [""]


def render_docstring(text: str) -> list[str]:
    if not text:
        return ["*No docstring.*", ""]
    out: list[str] = []
    for title, lines in split_sections(text):
        if title is None:
            out += prose(lines)
            continue
        heading = "Examples" if title == "Example" else title
        out += [f"**{heading}**", ""]
        out += parameter_list(lines, title) if title in LIST_SECTIONS else prose(lines)
    return out


# ----------------------------------------------------------------------------------------- output

def _kind(obj) -> str:
    if inspect.isclass(obj):
        if issubclass(obj, Warning):
            return "warning"
        if issubclass(obj, BaseException):
            return "exception"
        return "class"
    return "function"


def _anchor(qualname: str) -> str:
    """An HTML id: the dotted name with dashes (case kept: ``Example`` and ``example`` differ)."""
    return qualname.replace(".", "-")


def _module_summary(name: str) -> str:
    doc = importlib.import_module(name).__doc__ or ""
    first = _blocks(inspect.cleandoc(doc).splitlines())
    return inline(" ".join(line.strip() for line in first[0])) if first else ""


def render_entry(entry: Entry) -> list[str]:
    obj, short = entry.obj, entry.qualname.rsplit(".", 1)[-1]
    out = [f'<a id="{_anchor(entry.qualname)}"></a>', "", f"#### `{entry.qualname}`", ""]
    sig = signature(obj, short)
    kind = _kind(obj)
    if sig and kind in ("class", "function"):
        out += ["```python", sig, "```", ""]
    elif kind != "function":
        bases = ", ".join(b.__name__ for b in obj.__bases__)
        out += [f"*{kind}* ({bases})", ""]
    out += render_docstring(docstring(obj))
    undocumented = []
    for name, member in entry.members:
        target = member.fget if isinstance(member, property) else member
        text = docstring(member)
        label = name if isinstance(member, property) else signature(target, name) or name
        if not text:
            undocumented.append(f"`{label}`" if isinstance(member, property) else f"`{label}`")
            continue
        title = f"{short}.{name}" + (" (property)" if isinstance(member, property) else "")
        out += [f"##### `{title}`", ""]
        if not isinstance(member, property):
            out += ["```python", signature(target, f"{short}.{name}") or f"{short}.{name}(...)", "```", ""]
        out += render_docstring(text)
    if undocumented:
        out += ["Other members: " + ", ".join(undocumented) + ".", ""]
    return out


def build() -> str:
    """The whole of docs/api.md."""
    lines = [
        "# API reference",
        "",
        "Generated from the docstrings by `python docs/build_api.py`; do not edit by hand (the test suite",
        "checks that this file is up to date). Tutorials: [docs/tutorial](tutorial/README.md).",
        "",
    ]
    packages = [(package, title, collect(package, extra)) for package, title, extra in PACKAGES]
    lines += ["## Contents", ""]
    for package, title, modules in packages:
        lines.append(f"- [**{package}**](#{_anchor(package)}): {title}")
        for module, entries in modules.items():
            links = ", ".join(f"[`{e.qualname.rsplit('.', 1)[-1]}`](#{_anchor(e.qualname)})" for e in entries)
            lines.append(f"  - `{module}`: {links}")
    lines.append("")
    for package, title, modules in packages:
        lines += [f'<a id="{_anchor(package)}"></a>', "", f"## {package}: {title}", ""]
        summary = _module_summary(package)
        if summary:
            lines += [summary, ""]
        for module, entries in modules.items():
            lines += [f"### `{module}`", ""]
            summary = _module_summary(module)
            if summary:
                lines += [summary, ""]
            for entry in entries:
                lines += render_entry(entry)
    text = "\n".join(lines)
    text = re.sub(r"\n{3,}", "\n\n", text).rstrip() + "\n"
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Generate docs/api.md from the docstrings.")
    parser.add_argument("--check", action="store_true", help="exit 1 if docs/api.md is out of date")
    args = parser.parse_args(argv)
    text = build()
    if args.check:
        current = OUTPUT.read_text(encoding="utf-8") if OUTPUT.exists() else ""
        if current != text:
            print(f"{OUTPUT.relative_to(ROOT)} is out of date: run `python docs/build_api.py`", file=sys.stderr)
            return 1
        print(f"{OUTPUT.relative_to(ROOT)} is up to date")
        return 0
    OUTPUT.write_text(text, encoding="utf-8")
    print(f"wrote {OUTPUT.relative_to(ROOT)} ({len(text.splitlines())} lines)")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
