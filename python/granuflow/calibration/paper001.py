"""Constants of paper 001 that calibration uses (docs/paper001_decisions.md, docs/references.md)."""
from __future__ import annotations

from .. import outputs

# Paper 001's scene (flowsheets/stoeckl_gf25_table1.yaml): its bed is `bed`, its outlet gas temperature `gas.T`.
D_VALUES = outputs.d_values("bed")
OBSERVABLE_GROUPS = {"size": D_VALUES, "moisture": ("bed.moisture", "bed.moisture_wet"), "T_gas_out": ("gas.T",)}
OBSERVABLE_DISPLAY = {m: outputs.GROUP_DISPLAY[g] for g, members in OBSERVABLE_GROUPS.items() for m in members}

# Table 5: standard deviations of the measurements (moisture and gas temperature absolute, SI; sizes relative).
TABLE5_SIGMA: dict[str, dict[str, float]] = {
    "bed.moisture": {"abs": 0.01},   # 1 wt%, kg/kg
    "gas.T": {"abs": 2.0},           # K
    **{d: {"rel": 0.07} for d in D_VALUES[:5]},
    "bed.d75": {"rel": 0.08}, "bed.d84": {"rel": 0.09}, "bed.d90": {"rel": 0.10}, "bed.d95": {"rel": 0.11},
}
# Table 1 levels (upper inlet temperature 80 degC as in Fig. 11, see docs/paper001_decisions.md), in edge units.
TABLE1_LEVELS = {"inlet.V_dot": ("m3/h", (600.0, 700.0, 800.0)), "inlet.T": ("degC", (40.0, 60.0, 80.0)),
                 "nozzle.mdot": ("g/min", (60.0, 90.0, 120.0))}
