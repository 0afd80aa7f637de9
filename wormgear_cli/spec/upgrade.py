"""``wormgear upgrade``: a drive file of the legacy two-table form rewritten as ``[[stage]]`` tables.

The legacy form ([gear_pair], [worm_pair], [assembly], [loads] and the stage limits of
[requirements]) is the train [worm, spur]: every key moves to its stage by
:data:`wormgear_cli.spec.stages.LEGACY_KEYS`, renamed where the stage form names it otherwise
(``assembly.wheel_eccentricity_mm`` -> ``runout_mm`` of ``[stage.wheel]``), its value text kept
byte for byte.  Comments travel with what they stand before: a comment block before a key moves
with the key, an inline comment stays on its line, the comment before a table header goes with
the table's new header (or, for [assembly] and [loads], whose keys go to both stages, before the
first of its keys), and a comment block separated from the next header by a blank line stays
after the key it follows.  Drive-level tables ([drive], [stiffness], [materials], the drive's
[requirements], [effects.*]) are copied as they are; ``[statistics]`` keys are rewritten to the
stage paths.  A file written with dotted keys or inline tables for its stages is rewritten from
its values, without its comments (said in :attr:`Upgrade.note`).

The result is checked: it must load, and give every stage exactly the values of the original.
"""

from __future__ import annotations

import re
from typing import NamedTuple

import tomli_w

from wormgear_cli.errors import SpecError
from wormgear_cli.spec import stages as st
from wormgear_cli.spec.loader import loads_spec, raw_copy, set_path

#: legacy table -> the stage table that takes it whole (its header comments go there)
_TABLE_MOVES = {"worm_pair": (1, ""), "worm_pair.worm": (1, "worm"), "worm_pair.wheel": (1, "wheel"),
                "gear_pair": (2, ""), "gear_pair.output_gear": (2, "gear"), "gear_pair.pinion": (2, "pinion")}
_HEADER = re.compile(r"^\s*\[(?!\[)\s*([^\]]+?)\s*\]\s*(#.*)?$")
_KEY = re.compile(r'^\s*("(?:[^"\\]|\\.)*"|[A-Za-z0-9_-]+)\s*=')


class Upgrade(NamedTuple):
    """The upgraded file's ``text`` and a ``note`` for the user (empty when comments were kept)."""

    text: str
    note: str = ""


class _Item(NamedTuple):
    table: str          # the legacy table it was in ("" = top level)
    key: str            # its key (unquoted)
    lines: list         # the key's lines (a multi-line value included), verbatim
    before: list        # comment/blank lines before it
    after: list         # comment lines after it (a trailing block of its table)


def upgrade_text(text: str, source: str = "<spec>") -> Upgrade:
    """The stage form of the legacy drive file ``text`` (module docstring).  Raises SpecError for a
    file that does not load, or that is already of the stage form."""
    spec = loads_spec(text, source)
    if spec.form == "stages":
        raise SpecError(f"{source}: already a drive of [[stage]] tables; nothing to upgrade")
    try:
        head, tables, items = _scan(text)
        out = _assemble(head, tables, items)
        note = ""
    except _Unscannable:
        out, note = _from_values(spec), "comments not kept: the file's stages use dotted keys or inline tables"
    new = loads_spec(out, source)
    for a, b in zip(spec.stages, new.stages):
        if st.record_values(a) != st.record_values(b):
            raise SpecError(f"{source}: the upgraded file does not give the same stages (please report this)")
    return Upgrade(out, note)


class _Unscannable(Exception):
    """The file uses TOML forms the line-based rewrite does not follow."""


def _value_end(lines: list[str], k: int) -> int:
    """Index after the last line of the value that starts on line ``k`` (brackets balanced outside
    strings and comments)."""
    depth, j = 0, k
    while j < len(lines):
        text = lines[j] if j > k else lines[j].split("=", 1)[1]
        if '"""' in text or "'''" in text:
            raise _Unscannable
        quote = None
        for ch in text:
            if quote:
                quote = None if ch == quote else quote
            elif ch in "\"'":
                quote = ch
            elif ch == "#":
                break
            elif ch in "[{":
                depth += 1
            elif ch in "]}":
                depth -= 1
        j += 1
        if depth <= 0:
            return j
    raise _Unscannable


def _scan(text: str) -> tuple[list, dict, list]:
    """(the lines before the first table, table -> (its header comment lines, inline comment), the key items)."""
    lines = text.splitlines()
    head: list[str] = []
    tables: dict[str, tuple[list, str]] = {}
    items: list[_Item] = []
    table, pending, k = None, [], 0
    while k < len(lines):
        line = lines[k]
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            pending.append(line)
            k += 1
            continue
        m = _HEADER.match(line)
        if m:
            name = m.group(1).replace(" ", "")
            trailing, own = _split_trailing(pending)
            if table is None:
                head, trailing, own = pending, [], []
            elif items and trailing:
                items[-1] = items[-1]._replace(after=items[-1].after + trailing)
            tables[name] = (own, m.group(2) or "")
            table, pending, k = name, [], k + 1
            continue
        if stripped.startswith("[["):
            raise _Unscannable
        km = _KEY.match(line)
        if not km or table is None:
            raise _Unscannable
        key = km.group(1).strip('"')
        end = _value_end(lines, k)
        value = line.split("=", 1)[1].split("#", 1)[0].strip()
        if table.split(".")[0] in ("gear_pair", "worm_pair", "assembly", "loads", "requirements") and (
                value.startswith("{") or "." in key):
            raise _Unscannable  # a stage's keys written as an inline table or dotted keys
        items.append(_Item(table, key, lines[k:end], pending, []))
        pending, k = [], end
    if pending and items:
        items[-1] = items[-1]._replace(after=items[-1].after + pending)
    return head, tables, items


def _split_trailing(block: list[str]) -> tuple[list, list]:
    """A comment block before a header split at its last blank line: (what trails the previous key,
    what stands before the header)."""
    blanks = [i for i, ln in enumerate(block) if not ln.strip()]
    if not blanks:
        return [], block
    cut = blanks[-1]
    return [ln for ln in block[:cut] if ln.strip()], block[cut + 1:]


def _rename(line: str, old: str, new: str) -> str:
    """``line`` (a key line) with its key ``old`` written as ``new``, the rest verbatim."""
    m = _KEY.match(line)
    assert m is not None, line  # called on key lines only
    return line[:m.start(1)] + (f'"{new}"' if m.group(1).startswith('"') else new) + line[m.end(1):]


def _assemble(head: list, tables: dict, items: list) -> str:
    """The new text: the head, [drive], the two [[stage]] tables, then the other drive-level tables."""
    placed: dict[tuple[int, str], list[str]] = {(i, m): [] for i in (1, 2) for m in ("", *st.MEMBERS[
        st.LEGACY_TRAIN[i - 1]])}
    drive_level: dict[str, list[str]] = {}
    shown_header: set[str] = set()
    for it in items:
        path = f"{it.table}.{it.key}"
        hit = st.LEGACY_KEYS.get(path)
        if hit is None:
            lines = it.lines
            if it.table == "statistics":
                lines = [_rename(it.lines[0], it.key, st.new_path(None, it.key))] + it.lines[1:]
            drive_level.setdefault(it.table, []).extend(it.before + lines + it.after)
            continue
        index = st.LEGACY_TRAIN.index(hit[0]) + 1
        member, _, key = hit[1].rpartition(".")
        block = []
        if it.table not in _TABLE_MOVES and it.table not in shown_header:
            own, inline = tables[it.table]
            block += [ln for ln in own if ln.strip()] + ([f"{inline}  (was [{it.table}])"] if inline else [])
            shown_header.add(it.table)
        block += it.before + [_rename(it.lines[0], it.key, key)] + it.lines[1:] + it.after
        placed[(index, member)].extend(block)
    out = list(head) + [
        "# Upgraded by `wormgear upgrade` from the legacy two-table form: the same drive as [[stage]] tables",
        "# listed from the motor to the output (the worm pair, then the spur pair).", ""]
    out += _drive_table("drive", tables, drive_level)
    for index, kind in enumerate(st.LEGACY_TRAIN, start=1):
        out += _stage_header(tables, index, "", kind) + [f'kind = "{kind}"'] + _strip_blank(placed[(index, "")])
        for member in st.MEMBERS[kind]:
            if placed[(index, member)]:
                out += [""] + _stage_header(tables, index, member, kind) + _strip_blank(placed[(index, member)])
        out.append("")
    for table in drive_level:
        if table != "drive":
            out += _drive_table(table, tables, drive_level)
    return "\n".join(out).rstrip("\n") + "\n"


def _strip_blank(lines: list[str]) -> list[str]:
    while lines and not lines[0].strip():
        lines = lines[1:]
    while lines and not lines[-1].strip():
        lines = lines[:-1]
    return lines


def _stage_header(tables: dict, index: int, member: str, kind: str) -> list[str]:
    legacy = next(t for t, v in _TABLE_MOVES.items() if v == (index, member))
    own, inline = tables.get(legacy, ([], ""))
    header = "[[stage]]" if not member else f"[stage.{member}]"
    return [ln for ln in own if ln.strip()] + [header + (f"  {inline}" if inline else "")]


def _drive_table(table: str, tables: dict, drive_level: dict) -> list[str]:
    if table not in drive_level and table not in tables:
        return []
    own, inline = tables.get(table, ([], ""))
    return ([ln for ln in own if ln.strip()] + [f"[{table}]" + (f"  {inline}" if inline else "")]
            + _strip_blank(drive_level.get(table, [])) + [""])


def _from_values(spec) -> str:
    """The stage form written from ``spec``'s document (no comments): every legacy key moved to its
    stage, the other tables as they are."""
    raw = raw_copy(spec)
    out: dict = {}
    stage_tables: list[dict] = [{"kind": k} for k in st.LEGACY_TRAIN]
    doc = {"stage": stage_tables}
    for table, content in raw.items():
        if table in ("gear_pair", "worm_pair", "assembly", "loads", "requirements"):
            for path, value in _flatten(content, table):
                hit = st.LEGACY_KEYS.get(path)
                target = st.new_path(spec.stages, path) if hit else path
                set_path(doc, target, value)
        elif table == "statistics":
            out[table] = {st.new_path(spec.stages, k): v for k, v in content.items()}
        else:
            out[table] = content
    drive = out.pop("drive", None)
    requirements = doc.pop("requirements", None)
    ordered = {**({"drive": drive} if drive is not None else {}), "stage": stage_tables, **out,
               **({"requirements": requirements} if requirements else {})}
    return tomli_w.dumps(ordered)


def _flatten(node, prefix: str):
    for k, v in node.items():
        if isinstance(v, dict):
            yield from _flatten(v, f"{prefix}.{k}")
        else:
            yield f"{prefix}.{k}", v
