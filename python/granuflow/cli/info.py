"""granuflow units [NAME] | kernels [FAMILY] | materials [NAME] | describe SCENE | docs: the reference, from the
registries."""
from __future__ import annotations

import csv
import json
import os
import sys

from .common import ConfigError

DESCRIBE_COLUMNS = ("param", "value", "unit", "default", "lower", "upper", "input", "source", "description")


def cmd_units(args) -> int:
    from .. import plugins, reference

    if args.name:
        if args.name not in reference.unit_types():
            raise ConfigError(f"units {args.name}: unknown unit type (allowed: {', '.join(reference.unit_types())})")
        sys.stdout.write(reference.unit_text(args.name))
        return 0
    origin = plugins.origins()["units"]
    for name, desc in reference.unit_types().items():
        print(f"{name:24s} {desc}" + (f" [plugin {origin[name]}]" if name in origin else ""))
    print("\n(granuflow units NAME: ports, settings, parameters and outputs of one unit type)")
    return 0


def cmd_kernels(args) -> int:
    from .. import plugins, reference

    ref = reference.kernel_reference()
    if args.family:
        if args.family not in ref:
            raise ConfigError(f"kernels {args.family}: unknown family (allowed: {', '.join(ref)})")
        sys.stdout.write(reference.kernel_markdown(args.family))
        return 0
    for family, entries in ref.items():
        print(f"{family}:")
        origin = plugins.origins().get(family, {})
        for e in entries:
            tag = f" [plugin {origin[e['name']]}]" if e["name"] in origin else ""
            print(f"  {e['name']:24s} {e['description']}{tag}")
    print("\n(granuflow kernels FAMILY: parameters and settings of every kernel of one family)")
    return 0


def cmd_materials(args) -> int:
    from .. import materials, reference

    if args.name:
        sys.stdout.write(reference.material_markdown(materials.material(args.name)))
        return 0
    for m in materials.catalogue():
        print(f"{m['name']:24s} {m['description']}")
    print("\n(granuflow materials NAME: its values, the parameters they set and their sources; a scene names one in "
          "particles: material: NAME)")
    return 0


def describe_rows(fs) -> list[dict]:
    rows = []
    for p in fs.params:
        s = fs.spec(p)
        rows.append({"param": p, "value": s["value"], "unit": s["unit"], "default": s["default"],
                     "lower": s["lower"], "upper": s["upper"], "input": s.get("input", False),
                     "source": s.get("source", ""), "description": s.get("description", "")})
    return rows


def cmd_describe(args) -> int:
    """Every parameter with every column, never truncated: a text table whose width follows the content (not the
    terminal), or CSV / JSON for a spreadsheet or a script."""
    from ..flowsheet import load
    from ..montecarlo.scene import Scene, is_scene

    rows = Scene(args.scene).describe_rows() if is_scene(args.scene) else describe_rows(load(args.scene))
    out = sys.stdout
    if args.format == "json":
        json.dump(rows, out, indent=1)
        out.write("\n")
    elif args.format == "csv":
        w = csv.DictWriter(out, fieldnames=DESCRIBE_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    else:
        cells = [[str(r[c]) if not isinstance(r[c], float) else f"{r[c]:.6g}" for c in DESCRIBE_COLUMNS] for r in rows]
        widths = [max(len(c), *(len(x[i]) for x in cells)) for i, c in enumerate(DESCRIBE_COLUMNS)]
        fmt = "  ".join(f"{{:{'<' if c in ('param', 'unit', 'source', 'description') else '>'}{w}}}"
                        for c, w in zip(DESCRIBE_COLUMNS, widths))
        print(fmt.format(*DESCRIBE_COLUMNS).rstrip())
        for x in cells:
            print(fmt.format(*x).rstrip())
    return 0


def cmd_draw(args) -> int:
    """The scene's flowsheet drawn by Graphviz into --out (its extension chooses the format)."""
    from ..diagram import Diagram
    from ..flowsheet import load

    diagram = Diagram(load(args.scene))
    try:
        path = diagram.save(args.out)
    except ValueError as e:
        raise ConfigError(f"--out {e}") from None
    except RuntimeError as e:
        print(f"granuflow: draw: {e}", file=sys.stderr)
        return 1
    print(f"flowsheet diagram: {path}")
    return 0


def cmd_report(args) -> int:
    """OUT_DIR/report.html for a finished output folder."""
    from ..report import write_report

    print(f"report: {write_report(args.out_dir)}")
    return 0


def cmd_docs(args) -> int:
    """Write (or, with --check, compare) the generated reference pages under a docs folder."""
    from .. import reference

    stale = []
    try:
        for rel, text in reference.pages().items():
            path = os.path.join(args.dir, rel)
            old = open(path).read() if os.path.exists(path) else None
            if old == text:
                continue
            stale.append(rel)
            if not args.check:
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "w") as f:
                    f.write(text)
    except OSError as e:  # a link loop, a file where a folder should be, no permission: named, never a traceback
        raise ConfigError(f"{'--check' if args.check else '--write'} {args.dir}: cannot "
                          f"{'read' if args.check else 'write'} {e.filename or args.dir}: "
                          f"{e.strerror or type(e).__name__}") from None
    if args.check and stale:
        raise ConfigError(f"{args.dir}: {len(stale)} generated pages are out of date ({', '.join(stale)}); "
                          "run granuflow docs --write DIR")
    if not args.quiet:
        print(f"{'checked' if args.check else 'wrote'} {len(reference.pages())} pages in {args.dir}"
              + (f" ({len(stale)} changed)" if stale and not args.check else ""))
    return 0
