#!/usr/bin/env python3
"""Validates JSON documents against docs/scene.schema.json with the
reference `jsonschema` package (draft-07).

usage: validate_schema.py SCHEMA FILE...   prints one line per file: "ok FILE"
or "invalid FILE: reason". Exit status 2 if the package is missing."""
import json
import sys

try:
    import jsonschema
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e}", file=sys.stderr)
    sys.exit(2)


def main(schema_path, files):
    schema = json.load(open(schema_path))
    jsonschema.Draft7Validator.check_schema(schema)
    validator = jsonschema.Draft7Validator(schema)
    for f in files:
        errors = sorted(validator.iter_errors(json.load(open(f))), key=lambda e: list(e.path))
        if errors:
            print(f"invalid {f}: {errors[0].message}")
        else:
            print(f"ok {f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
