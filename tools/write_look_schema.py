"""Writes look/look.schema.json from the parameter table, through the built Python module.

    PYTHONPATH=build/python python3 tools/write_look_schema.py

A test compares the file with darkroom.look_schema(), so run this after changing the table.
"""
import json
import os

import darkroom

path = os.path.join(os.path.dirname(__file__), "..", "look", "look.schema.json")
with open(path, "w") as f:
    json.dump(darkroom.look_schema(), f, indent=2)
    f.write("\n")
