"""Writes the look's reference from the parameter table, through the built Python module:
look/look.schema.json (the look files' JSON Schema) and docs/reference/look-parameters.md.

    PYTHONPATH=build/python python3 tools/write_look_reference.py

A test compares both with what the table gives, so run this after changing the table.
"""
import json
import os
import sys

import darkroom

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def text(value):
    if value is None:
        return "unset"
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, list):
        return ",".join(text(v) for v in value)
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value) if value != "" else '""'


def parameters_page():
    """The table as a page: one row a setting, each front end's name for it."""
    rows = [
        "# Look parameters",
        "",
        "Every setting of a look, as the program's flags, the plugin's parameters, the Python",
        "module's keywords and look files name it. Made from the parameter table",
        "(`look/parameters.cpp`) by `tools/write_look_reference.py`; a test keeps it current.",
        "Ranges are what every front end accepts; the plugin's sliders may show less.",
        "",
        "| look-file key | flag | plugin | Python | default | range | unit | help |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for p in darkroom.parameters():
        value_range = f"{text(p['min'])} to {text(p['max'])}" if "min" in p else \
            " \\| ".join(p["choices"]) if "choices" in p else ""
        plugin = f"{p['label']} (`{p['ofx_name']}`)" if p["ofx_name"] else "-"
        help_text = p["help"].replace("|", "\\|") + (" *Animatable in the plugin.*" if p["animatable"] else "")
        rows.append(f"| `{p['key']}` | `--{p['key']}` | {plugin} | `{p['keyword']}=` | {text(p['default'])} | "
                    f"{value_range} | {p['unit']} | {help_text} |")
    return "\n".join(rows) + "\n"


def schema_text():
    return json.dumps(darkroom.look_schema(), indent=2) + "\n"


if __name__ == "__main__":
    outputs = {os.path.join(ROOT, "docs", "reference", "schemas", "look.schema.json"): schema_text(),
               os.path.join(ROOT, "docs", "reference", "look-parameters.md"): parameters_page()}
    for path, content in outputs.items():
        with open(path, "w") as f:
            f.write(content)
        print("wrote", os.path.relpath(path, ROOT), file=sys.stderr)
