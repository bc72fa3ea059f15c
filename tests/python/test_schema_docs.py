"""The scene schema (`flexmor --schema`, declared once in src/io/io_schema_tables.f90) and the tables
of docs/input.md describe the same variables: each variable of a group's table is in the
schema and each schema variable in its group's table, with the same unit."""
import re
import subprocess

from helpers import BIN, ROOT


def schema():
    out = subprocess.run([BIN, "--schema"], capture_output=True, text=True, timeout=60,
                         check=True).stdout
    rows = [line.split("\t") for line in out.splitlines()]
    header, rows = rows[0], rows[1:]
    assert header[:4] == ["group", "name", "type", "units"]
    return {(r[0], r[1]): r for r in rows}


def documented():
    """(group, name) -> unit text, from the first table ('| variable |') of each &group."""
    text = (ROOT / "docs" / "input.md").read_text()
    found = {}
    for section in re.split(r"\n### &", text)[1:]:
        group = section.split("\n", 1)[0].strip()
        body = re.split(r"\n## |\n### ", section)[0]
        lines = body.split("\n")
        start = next(i for i, line in enumerate(lines) if line.startswith("| variable"))
        for line in lines[start + 2:]:
            if not line.startswith("|"):
                break
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            names = re.findall(r"`([^`]+)`", cells[0])
            units = cells[2].split(", ")
            # `times`, `values` | s, rad: one unit per name where the row gives one each.
            if len(units) != len(names):
                units = [cells[2]] * len(names)
            for name, unit in zip(names, units):
                found[(group, name)] = unit
    return found


def test_every_variable_documented_and_declared():
    declared, docs = schema(), documented()
    assert len(declared) > 90
    assert sorted(set(declared) - set(docs)) == [], "declared but not in docs/input.md"
    assert sorted(set(docs) - set(declared)) == [], "in docs/input.md but not declared"


def test_units_agree():
    declared, docs = schema(), documented()
    norm = lambda u: "" if u in ("", "–", "-") else u
    wrong = {k: (declared[k][3], docs[k]) for k in declared
             if norm(declared[k][3]) != norm(docs[k])}
    assert wrong == {}


def documented_ranges():
    """(group, name) -> range text, from the table of the 'Value ranges' section."""
    text = (ROOT / "docs" / "input.md").read_text()
    section = text.split("\n## Value ranges\n", 1)[1].split("\n## ", 1)[0]
    found = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("`"):
            found[(cells[0].strip("`"), cells[1].strip("`"))] = cells[2]
    return found


def test_ranges_agree():
    """Every declared range is in the table with the same text, and nothing else is."""
    declared = {k: r[5] for k, r in schema().items() if r[5]}
    assert len(declared) > 60
    assert documented_ranges() == declared
