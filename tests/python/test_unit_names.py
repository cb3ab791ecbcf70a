"""No unit name is special: the headline scene with its bed called ``fb`` and its gas ``air`` (connections, links,
summary and plots renamed with them) gives the same summary, observable groups and plots as the original. The
generic modules (granuflow.outputs, granuflow.plots) read the scene's own declarations, never the names bed and gas."""
import re

import pytest

from conftest import SCENE, gf

from granuflow import outputs
from granuflow.plots.spec import plot_specs

RENAMED = {"bed": "fb", "gas": "air"}


def renamed_text() -> str:
    text = open(SCENE).read()
    for old, new in RENAMED.items():
        text = re.sub(rf"^  {old}:", f"  {new}:", text, flags=re.M)  # the unit's entry under units:
        text = re.sub(rf"\b{old}\.", f"{new}.", text)  # its ports, outputs and parameters: bed.d50, gas.state
    return text


def rename(obj):
    """The original's names as the renamed scene spells them (in keys, values and messages)."""
    if isinstance(obj, dict):
        return {rename(k): rename(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(rename(v) for v in obj)
    if isinstance(obj, str):
        for old, new in RENAMED.items():
            obj = re.sub(rf"(?<![\w.]){old}(?=[.:])", new, obj)
            obj = obj.replace(f"({old})", f"({new})").replace(f"'{old}'", f"'{new}'")
        return obj
    return obj


@pytest.fixture(scope="module")
def both():
    text = renamed_text()
    assert "  fb:" in text and "air.state -> fb.gas" in text and "fb.T0: inlet.T" in text
    return [(fs, fs.simulate(warn=False)) for fs in (gf.load(SCENE), gf.load_text(text, "renamed.yaml"))]


def test_summary_is_the_same(both):
    (fa, a), (fb, b) = both
    assert fb.summary_map == rename(fa.summary_map)
    sa, sb = a.summary, b.summary
    for s in (sa, sb):
        s.pop("wall_time_s")
        s.pop("scene")
    assert sb == rename(sa)  # every value equal, the unit names in keys and messages renamed
    assert sb["d50_um"] == sa["d50_um"] and sb["T_gas_out_K"] == sa["T_gas_out_K"]


def test_observable_groups_follow_the_scene(both):
    (fa, _), (fb, _) = both
    ga, gb = (outputs.observable_groups(f.summary_map, f.state_names + f.output_names) for f in (fa, fb))
    assert ga == {"size": outputs.d_values("bed"), "moisture": ("bed.moisture", "bed.moisture_wet"),
                  "T_gas_out": ("gas.T",)}  # paper 001's observable groups, as they were by name
    assert gb == rename(ga)
    assert outputs.observable_display("air.T", gb) == "degC" and outputs.observable_display("fb.d50", gb) == "um"
    assert outputs.observable_display("air.Y", gb) is None
    # a bed without d5..d95 and moisture on both bases (paper 003's chambers) forms no group: its own panels
    assert outputs.observable_groups({"d50_um": "drying.d50"}, ["drying.d10", "drying.d50", "drying.d90"]) == {}


def test_plots_are_the_same(both, monkeypatch, tmp_path):
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from granuflow.plots import plot_psd, plot_series

    drawn = []

    def record(fig, path, **kw):  # what each figure shows, instead of the image file
        ax = fig.axes[0]
        drawn.append({"title": ax.get_title(), "x": ax.get_xlabel(), "y": ax.get_ylabel(),
                      "legend": [t.get_text() for t in ax.get_legend().get_texts()],
                      "lines": [(line.get_xdata().tolist(), line.get_ydata().tolist()) for line in ax.get_lines()]})

    monkeypatch.setattr(Figure, "savefig", record)
    per_scene = []
    for fs, res in both:
        drawn.clear()
        for k, spec in enumerate(plot_specs(fs)):
            if spec.get("kind") == "psd":
                plot_psd(res, str(tmp_path / "psd.png"), [t * 60.0 for t in spec["times_min"]])
            else:
                plot_series(res, spec, str(tmp_path / f"plot_{k}.png"))
        per_scene.append(list(drawn))
    original, renamed = per_scene
    assert len(original) == 4 and all(p["lines"] for p in original)
    assert renamed == rename(original)
