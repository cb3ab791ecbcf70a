"""Flowsheets loaded from scene files: parameters by "unit.param", inputs, simulation."""
from __future__ import annotations

import math
import os
import warnings
from collections.abc import Iterable, Mapping, Sequence

from . import _core, accuracy, outputs
from .accuracy import grid_check as _grid_check
from .quantity import bool_types, integer_types, is_number, parse_time
from .result import BalanceWarning, GridWarning, Layout, Result
from .textfile import check_regular, short

ConfigError = _core.ConfigError
# The accuracy target of a scene that leaves its size grid to granuflow (particles: without classes): the threshold
# of the grid check (granuflow.accuracy.grid_check.THRESHOLD), so that such a scene is converged to what a plain run
# would accept without a warning.
DEFAULT_ACCURACY = 0.02


class Flowsheet:
    """A flowsheet built from a scene file.

    Parameters are addressed as ``"unit.param"``; values are SI floats or strings with a unit
    (``"60 degC"``, ``"90 g/min"``). Changing a parameter never rebuilds the flowsheet.
    """

    def __init__(self, scene: "_core.Scene"):
        self._scene = scene
        self._layout: Layout | None = None  # what every result of this flowsheet shares, from its first run
        self._summary_map: dict = {}

    # -- identity -------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self._scene.name

    @property
    def path(self) -> str:
        return self._scene.path

    @property
    def description(self) -> str:
        return self._scene.description

    @property
    def t_end(self) -> float:
        """Default end time of a run in s (from the scene file)."""
        return self._scene.t_end

    @property
    def params(self) -> list[str]:
        return self._scene.param_names()

    @property
    def state_names(self) -> list[str]:
        return self._scene.state_names()

    @property
    def output_names(self) -> list[str]:
        return self._scene.output_names()

    @property
    def output_roles(self) -> list[tuple]:
        """(role, quantity, class, unit) per reported output, in ``output_names`` order (granuflow.outputs reads
        them: size distributions, balance terms)."""
        return [tuple(r) for r in self._scene.output_roles()]

    @property
    def text(self) -> str:
        """The scene text the flowsheet was built from (what a remote worker rebuilds it from)."""
        return self._scene.text

    @property
    def summary_map(self) -> dict[str, str]:
        """The scene's summary keys and the state or output each one reads (``{"d50_um": "bed.d50", ...}``)."""
        return dict(self._scene.summary_map)

    def summary_keys(self) -> list[str]:
        """Every key of this scene's summary.json that holds a number: the standard ones, then the scene's."""
        std = list(outputs.STANDARD_SUMMARY_KEYS)
        return std + [k for k in self._scene.summary_map if k not in std]

    def unit_of(self, name: str) -> str:
        """SI unit of a state or reported output (or of an observable of calibration, e.g. a size fraction);
        ConfigError listing the valid names otherwise."""
        if not hasattr(self, "_units"):  # the structure never changes: asked once
            self._units = self.units()
        if name in self._units:
            return self._units[name]
        from . import _calibration  # what only calibration observes (loads Ceres: only then), or the error

        return _calibration.observable_unit(self._scene, name)

    def value_unit(self, name: str) -> str:
        """The unit of a summary key's value (``d50_um``: um) or of a state/output (SI)."""
        smap = self._scene.summary_map
        if name in smap:
            return outputs.summary_unit(name, self.unit_of(smap[name]))
        if name in outputs.STANDARD_SUMMARY_UNITS:
            return outputs.STANDARD_SUMMARY_UNITS[name]
        return self.unit_of(name)

    @property
    def material(self) -> dict | None:
        """The solid the scene names (``particles: material:``, docs/materials.md): ``name`` (None when the scene
        names none: the units' built-in values, paper 001's maltodextrin, apply), ``built_in``: the parameters that
        keep a built-in value because the named material gives none, with that value (SI). None without a particle
        system."""
        if self.grid() is None:
            return None
        name = self._scene.material or None
        built_in = {q: self.get(q) for q in self._scene.material_unsupplied}
        note = ("no material named: the solid's values are the units' built-in ones (paper 001's maltodextrin); "
                "name one with particles: material: NAME (granuflow materials)") if name is None else (
            f"material {name} gives no value for {', '.join(built_in)}: built-in (paper 001) values used; set them "
            "in the scene's params" if built_in else None)
        return {"name": name, "built_in": built_in, "note": note}

    def units(self) -> dict[str, str]:
        """SI unit of every state and reported output."""
        return dict(_core.scene_units(self._scene))

    def parameter_values(self) -> dict[str, float]:
        """Every parameter's current value (SI)."""
        return {p: self.get(p) for p in self.params}

    @property
    def extra(self) -> dict:
        """Scene keys the core does not interpret (plots, sweep, notes, accuracy), typed as PyYAML types YAML."""
        return {k: self.section(k) for k in ("plots", "sweep", "notes", "accuracy") if k in self._scene.sections_json}

    def section(self, key: str):
        """A section of the scene the Python layer reads (plots, sweep, notes, accuracy, particles, inputs, events)
        as Python values, or None when the scene has none: the core parsed the file once (held to the limits of every
        YAML file) and hands the section over as JSON, its scalars typed as PyYAML's safe loader types them."""
        text = self._scene.sections_json.get(key)
        if text is None:
            return None
        import json

        return json.loads(text)

    # -- parameters -----------------------------------------------------------------------------
    def get(self, name: str) -> float:
        """Current value of ``name`` in SI units."""
        return self._scene.get(name)

    def set(self, name: str, value: float | str) -> "Flowsheet":
        """Set ``name`` (SI float, or string with a unit). Raises ConfigError outside the bounds."""
        if isinstance(value, bool_types()):  # True is an int to Python, but never a parameter value
            raise ConfigError(f"parameter {name} = {value}: expected a number (SI) or a string with a unit, e.g. "
                              "'60 degC', not a bool")
        self._scene.set(name, value)
        return self

    def update(self, values: Mapping[str, float | str]) -> "Flowsheet":
        if not isinstance(values, Mapping):
            raise ConfigError(f"update({short(values)}): expected a mapping {{'unit.param': value}}")
        for k, v in values.items():
            self.set(k, v)
        return self

    def spec(self, name: str) -> dict:
        """Declared unit, bounds, default, description and source of a parameter."""
        return self._scene.spec(name)

    def describe(self):
        """All parameters as a pandas DataFrame (value, SI unit, bounds, source)."""
        import pandas as pd

        rows = [{"param": p, **self.spec(p)} for p in self.params]
        return pd.DataFrame(rows).set_index("param")

    def set_input(self, name: str, times: Sequence[float], values: Sequence[float | str], *,
                  interp: str = "linear") -> "Flowsheet":
        """Drive parameter ``name`` by a piecewise-linear (or ``interp="step"``) function of time (s)."""
        self._scene.set_input(name, _times(times, f"set_input({name!r}): times"), list(values), interp)
        return self

    def set_t_end(self, t_end: float | str) -> "Flowsheet":
        """The default end time of a run: seconds, or a string with a time unit (``"60 min"``), > 0."""
        self._scene.set_t_end(_end_time(t_end, "set_t_end()"))
        return self

    def grid(self) -> dict | None:
        """The size grid of the scene's ``particles:`` section (its settings, defaults included, as text), or None
        when the scene has none."""
        settings = self.unit_settings().get("particles")
        return dict(settings[1]) if settings and settings[0] == "particles" else None

    def size_edges(self, unit: str) -> list[float]:
        """The class edges (m, volume-equivalent diameters) of the size distribution ``unit`` reports (empty when it
        reports none with edges): the grid a measured table is mapped onto (granuflow.measured_psd)."""
        return list(_core.unit_size_edges(self._scene, unit))

    def refined(self, factor: int) -> "Flowsheet":
        """The same flowsheet on a size grid ``factor`` times finer over the same range of sizes (log-diameter
        grids: the pivot spacing divided by ``factor``, so every old pivot is a new one; geometric grids: ``factor``
        times the classes per doubling of volume; a 2-D population's liquid axis: ``factor`` times its classes),
        with this flowsheet's parameter values. ConfigError when the scene has no size grid or the finer one
        exceeds the grid's limits."""
        if not isinstance(factor, int) or isinstance(factor, bool) or factor < 1:
            raise ConfigError(f"refined(factor = {short(factor)}): expected a whole number >= 1")
        return self.regridded(factor)

    def regridded(self, factor: float) -> "Flowsheet":
        """:meth:`refined` by any factor > 0 (below 1: coarser), the class counts rounded (granuflow.accuracy
        chooses grids between the nested ones)."""
        g = self.grid()
        if g is None:
            raise ConfigError(f"{self.path or self.name}: no size grid (particles: section) to refine")
        n = int(g["classes"])
        if g.get("grid", "log_diameter") == "geometric":
            q = max(1, round(int(g["q"]) * factor))
            new = {"q": q, "classes": max(2, round(n * q / int(g["q"])))}
        else:
            new = {"classes": max(3, round((n - 1) * factor) + 1)}
        label = self.path or self.name
        text = _with_grid_settings(self.text, new, label)
        for unit, nl in self._liquid_classes().items():
            text = _with_grid_settings(text, {"liquid_classes": max(2, round(nl * factor))}, label,
                                       ("units", unit))
        fs = load_text(text, f"{label} (grid refined {factor:g}x)")
        fs.copy_values_from(self)
        fs.set_t_end(self.t_end)
        return fs

    def with_settings(self, settings: Mapping[str, object]) -> "Flowsheet":
        """A new flowsheet with unit settings changed (``{"particles.classes": 40, "bed.aggregation": "constant",
        "particles.d_max": "3 mm"}``): a setting shapes the structure, so the scene text is built again with the
        values checked as in a scene file; this flowsheet's parameter values and end time carry over
        (:mod:`granuflow.structure`)."""
        from . import structure

        if not isinstance(settings, Mapping):
            raise ConfigError(f"with_settings({short(settings)}): expected a mapping {{'unit.setting': value}}")
        return structure.with_settings(self, settings, "with_settings():")

    def _liquid_classes(self) -> dict[str, int]:
        """The liquid classes of every 2-D population (unit settings ``liquid_classes``)."""
        return {u: int(s[1]["liquid_classes"]) for u, s in self.unit_settings().items()
                if "liquid_classes" in s[1]}

    def grid_label(self) -> str:
        """The grid's size for messages: ``classes 10`` (``q 8, classes 40`` on a geometric grid; a 2-D
        population's liquid classes after an x: ``classes 40 x 40``); "" without a size grid."""
        g = self.grid()
        if g is None:
            return ""
        lab = f"q {g['q']}, classes {g['classes']}" if g.get("grid") == "geometric" else f"classes {g['classes']}"
        return lab + "".join(f" x {nl}" for nl in self._liquid_classes().values())

    def copy_values_from(self, other: "Flowsheet") -> "Flowsheet":
        """Every constant parameter value of ``other`` (a flowsheet of the same scene), links respected; an input
        set from Python that the scene text does not hold cannot be carried over (ConfigError)."""
        declared = other.section("inputs") or {}
        pending = []
        for p in other.params:
            spec = other.spec(p)
            if spec.get("input"):
                if p not in declared:
                    raise ConfigError(f"{p}: driven by an input set from Python (set_input), which only the scene "
                                      "text could carry to another grid; declare it under the scene's inputs:")
                continue
            pending.append((p, spec["value"]))
        for _ in range(2):  # a link target follows its source: set it after the source
            failed = []
            for p, v in pending:
                try:
                    self.set(p, v)
                except ConfigError:
                    failed.append((p, v))
            pending = failed
        for p, v in pending:
            self.set(p, v)  # raises, naming the parameter
        return self

    def clone(self) -> "Flowsheet":
        """An independent copy with the same parameter values (for threads and sweeps)."""
        return Flowsheet(self._scene.clone())

    def unit_settings(self) -> dict:
        return self._scene.unit_settings()

    def setting_specs(self) -> dict[str, list[dict]]:
        """Per unit its declared settings: name, type, value in use, choices, lower, upper, description."""
        return self._scene.setting_specs()

    def from_text(self, text: str) -> "Flowsheet":
        """A flowsheet built from ``text`` (this scene changed), named as this one in messages."""
        return load_text(text, self.path or self.name)

    # -- simulation -----------------------------------------------------------------------------
    def steady_state(self, *, t: float = 0.0, ftol: float = 1e-10, max_iterations: int = 200,
                     max_pseudo_steps: int = 2000, stability: bool = False) -> dict:
        """Steady state F(y, y' = 0) = 0 with inputs evaluated at ``t``: Newton (KINSOL) from consistent initial
        values, pseudo-transient continuation when Newton alone fails. Quantities the equations conserve (a batch
        hold-up) keep their initial values and are listed under ``conserved``. Returns ``{"y": {state: value},
        "iterations", "residual_norm", "method", "pseudo_steps", "conserved", "warnings", "wall_time_s", "outputs",
        "boundary_flows", "stability"}`` (``warnings`` names a trivial root, e.g. an emptied population; ``outputs``
        the reported outputs at the steady state, NaN for amounts integrated over time; ``boundary_flows`` per
        balance quantity the flows in and out of the flowsheet, per second). With ``stability``, ``stability`` holds
        the eigenvalue of the linearized dynamics with the largest real part (``max_real_eigenvalue``,
        ``imag_of_max`` in 1/s): positive means the steady state is unstable (the dynamics oscillate around it), else
        None. Raises SolverError when the flowsheet has no steady state (a quantity that changes at a constant rate,
        such as a batch being sprayed) or none is found, naming the time and the unit."""
        return self._scene.steady_state(t=float(t), ftol=float(ftol), max_iterations=int(max_iterations),
                                        max_pseudo_steps=int(max_pseudo_steps), stability=bool(stability))

    def simulate(self, t_end: float | None = None, *, t_out: Iterable[float] | None = None,
                 n_out: int | None = None, rtol: float | None = None, atol: float | None = None,
                 sensitivities: Sequence[str] = (), linear_solver: str | None = None,
                 max_steps: int | None = None, method: str | None = None, warn: bool = True,
                 error_estimate: bool = False, accuracy=None, grid_check: bool | None = None,
                 checkpoints: Iterable[float] | None = None, checkpoint_dir: str | None = None,
                 restart: str | None = None) -> Result:
        """Integrate the flowsheet; the GIL is released during the solve.

        ``method``: ``auto`` (default: IDAS for a DAE, for an ODE chosen by its stiffness), ``ida``, ``bdf``,
        ``adams`` or ``erk`` (the last three for ODE flowsheets); ``result.stats["method"]`` and
        ``["method_reason"]`` say what ran and why.

        Raises ``SolverError`` (with ``.t``, ``.unit``, ``.worst_residual``) if the integrator fails and
        ``ConfigError`` for invalid options; ``BalanceError`` (a SolverError, with ``.balance``, ``.value`` and
        ``.result``) when a balance closure is far above its limit (a unit loses or creates mass or energy).
        ``Result.warnings`` says when a size grid clips the distribution (at the start or later) or a balance closes
        worse than the tolerance explains; with ``warn`` (default) each is also issued as a :class:`GridWarning` or
        :class:`BalanceWarning`.
        ``error_estimate``: re-solve at a 100 times tighter tolerance and on size grids refined twice and four
        times, and attach the estimated numerical error of every summary output and time series as
        ``Result.error_estimate`` (:mod:`granuflow.accuracy`; also in ``Result.summary`` and the plots).
        ``accuracy``: a relative error (``0.01``, ``"1%"``) or a mapping per summary key: the grid and tolerance
        are refined until the estimated numerical error of every (named) summary output is below it
        (:mod:`granuflow.accuracy.target`); the result is the solve on that grid, ``Result.accuracy`` says what
        was reached and at what cost. Default: the scene's ``accuracy:``; a scene whose ``particles:`` gives no
        ``classes`` gets DEFAULT_ACCURACY (its grid is then chosen to converge); ``False``: none.
        ``grid_check`` (default: ``warn``, for flowsheets of up to grid_check.PYTHON_MAX_STATES unknowns): one solve
        on a grid twice as fine estimates the grid error of every summary output and warns above 2 %
        (:mod:`granuflow.accuracy.grid_check`; ``Result.grid_check``).
        ``checkpoints`` (s; default: the scene's ``checkpoints:``), ``checkpoint_dir``, ``restart``: checkpoint
        times, the folder their files are written to, and a checkpoint file to resume from
        (docs/events_and_checkpoints.md).
        """
        if not isinstance(error_estimate, bool_types()):
            raise ConfigError(f"simulate(): error_estimate = {short(error_estimate)}: expected True or False")
        if grid_check is not None and not isinstance(grid_check, bool_types()):
            raise ConfigError(f"simulate(): grid_check = {short(grid_check)}: expected True or False")
        target = self._accuracy_target(accuracy)
        if target is not None:
            from .accuracy import target as acc_target

            if sensitivities:
                raise ConfigError("simulate(): sensitivities with an accuracy target: run simulate(accuracy=False) "
                                  "on the grid the target chose (Result.accuracy.grid)")
            res = acc_target.solve(self, target, t_end=t_end, t_out=t_out, n_out=n_out, rtol=rtol, atol=atol,
                                   linear_solver=linear_solver, max_steps=max_steps, method=method)
            if error_estimate:
                res.error_estimate = res.flowsheet._error_estimate(res, linear_solver=linear_solver,
                                                                   max_steps=max_steps, method=method)
            self._warn(res, warn)
            return res
        if t_out is not None:
            t_out = _times(t_out, "simulate(): t_out")
            if not t_out:  # as the scene file's `output: {times: []}`: an empty list is a mistake, not "default"
                raise ConfigError("simulate(): t_out = []: expected a non-empty list of times in [0, t_end] "
                                  "(or leave it out, or give n_out)")
        for key, v in (("n_out", n_out), ("max_steps", max_steps)):
            if v is not None and (isinstance(v, bool_types()) or not isinstance(v, integer_types())):
                raise ConfigError(f"simulate(): {key} = {short(v)}: expected a whole number")
        for key, v in (("rtol", rtol), ("atol", atol)):
            if v is not None and not is_number(v):
                raise ConfigError(f"simulate(): {key} = {short(v)}: expected a finite number")
        if isinstance(sensitivities, str):
            raise ConfigError(f"simulate(): sensitivities = {short(sensitivities)}: expected a list of parameter "
                              "names, e.g. ['inlet.T']")
        t_end = None if t_end is None else _end_time(t_end, "simulate()")
        ahead = self._grid_check_ahead(grid_check, warn, checkpoints, restart, t_end=t_end, t_out=t_out,
                                       n_out=n_out, rtol=rtol, atol=atol, linear_solver=linear_solver,
                                       max_steps=max_steps, method=method)
        try:
            return self._simulate(t_end, t_out, n_out, rtol, atol, sensitivities, linear_solver, max_steps, method,
                                  warn, error_estimate, grid_check, checkpoints, checkpoint_dir, restart, ahead)
        except KeyboardInterrupt:  # raised in Python, before or after the run's solve: the check's solve stops too
            if ahead is not None:
                ahead.cancel()
            raise
        finally:
            if ahead is not None:  # also when the run failed: no solve left running behind an exception
                ahead.join()

    def _grid_check_ahead(self, grid_check, warn, checkpoints, restart, **kw):
        """The grid check's solve started before the run (grid_check.Ahead), where the run is sure to be checked
        and writes no checkpoints, for flowsheets within the default check's limit (every state of the scene counted:
        an upper bound of the integrator's unknowns, which a result tells). There the finer solve costs a few times
        a short run; a larger flowsheet's would keep running for as long after the run stopped (an interrupt, a
        failure), so it is checked after its run, as before. None otherwise, or when the finer grid cannot be made
        (the check then says why, as before)."""
        if grid_check is False or restart or checkpoints is not None or self.scene_checkpoints or self.grid() is None:
            return None
        n = self._scene.n_states()
        if n > _grid_check.PYTHON_MAX_STATES or (grid_check is None and not self._checks_grid_by_default(warn, n)):
            return None
        try:
            return _grid_check.Ahead(self, **kw)
        except ConfigError:
            return None

    def _checks_grid_by_default(self, warn: bool, unknowns: int) -> bool:
        """Whether simulate() checks the grid when not told (grid_check=None): when it warns, the scene does not keep
        its grid as written (`accuracy: false`), and the flowsheet has at most grid_check.PYTHON_MAX_STATES
        ``unknowns``."""
        return bool(warn) and self.scene_accuracy is not False and unknowns <= _grid_check.PYTHON_MAX_STATES

    def _simulate(self, t_end, t_out, n_out, rtol, atol, sensitivities, linear_solver, max_steps, method, warn,
                  error_estimate, grid_check, checkpoints, checkpoint_dir, restart, ahead) -> Result:
        layout = self._layout  # names, roles and units: the first run brings them
        raw = self._scene.simulate(
            t_end=t_end, t_out=t_out, n_out=None if n_out is None else int(n_out), rtol=rtol, atol=atol,
            sensitivities=list(sensitivities), linear_solver=linear_solver,
            max_steps=None if max_steps is None else int(max_steps), method=method, names=layout is None,
            checkpoints=None if checkpoints is None else _times(checkpoints, "simulate(): checkpoints"),
            checkpoint_dir=checkpoint_dir or "", restart=restart or "")
        if layout is None:
            layout = self._layout = Layout(raw, self.units())
            self._summary_map = dict(self._scene.summary_map)
        res = Result(raw, scene_name=self.name, summary_map=self._summary_map, layout=layout)
        res.material = self.material
        res.flowsheet = self
        res.check_balance()  # a unit that loses mass is an error, not a number in a file
        res.extra_warnings += self._unfired_events(res)
        if error_estimate:
            res.error_estimate = self._error_estimate(res, linear_solver=linear_solver, max_steps=max_steps,
                                                      method=method)
        if grid_check is None:  # a scene's `accuracy: false` keeps its grid as written, unchecked
            grid_check = self._checks_grid_by_default(warn, res.stats["states"])
        if grid_check:
            from .accuracy import grid_check as gc

            res.grid_check = gc.check(self, res, ahead, linear_solver=linear_solver, max_steps=max_steps,
                                      method=method)
        self._warn(res, warn)
        return res

    def _unfired_events(self, res: Result) -> list[str]:
        """A declared one-shot event that never fired in a run that reached its end is named: an event fires on a
        crossing, so a recipe step whose condition already held when it was armed, or never got there, would otherwise
        pass unnoticed. A repeating event is a switching law (a valve's positions): that one of its switches was never
        needed in this run is not a finding."""
        t = res._t_list()
        if "events:" not in self.text or not t or t[-1] < t[0] + (self.t_end - t[0]) * (1 - 1e-12):
            return []  # no events, or a stop event ended the run early (the later ones had no chance)
        declared = self.section("events") or []
        fired = {e["name"] for e in res.events}
        return [f"event {e.get('name')} ({e.get('when')}) never fired: its condition did not cross during the run "
                "(an event fires on a crossing, not where its condition already holds when it is armed; "
                "docs/events_and_checkpoints.md)"
                for e in declared if isinstance(e, dict) and e.get("name") not in fired and not e.get("repeat")]

    def _warn(self, res: Result, warn: bool) -> None:
        if warn:
            for w in res.warnings:
                kind = BalanceWarning if w.startswith("balance:") else GridWarning
                warnings.warn(f"{self.path or self.name}: {w}", kind, stacklevel=3)

    def _accuracy_target(self, accuracy) -> dict | None:
        """The accuracy target of a run (granuflow.accuracy.target.parse_target) or None: ``accuracy`` given, else
        the scene's ``accuracy:``, else DEFAULT_ACCURACY when the scene's particles: give no classes."""
        if accuracy is False:
            return None
        if accuracy is not None:
            from .accuracy import target as acc_target

            return acc_target.parse_target(accuracy, "simulate(): accuracy")
        scene = self.scene_accuracy
        if scene is not None:
            from .accuracy import target as acc_target

            return None if scene is False else acc_target.parse_target(scene, f"{self.path or self.name}: accuracy")
        return {"*": DEFAULT_ACCURACY} if self._grid_without_classes() else None

    @property
    def scene_checkpoints(self) -> list[float]:
        """The scene's ``checkpoints:`` times (s), empty without (docs/events_and_checkpoints.md)."""
        return list(self._scene.checkpoints)

    @property
    def scene_accuracy(self):
        """The scene's ``accuracy:`` as written (None without one; ``False``: its grid as written, unchecked)."""
        if not hasattr(self, "_scene_accuracy"):  # the scene text never changes: read once
            self._scene_accuracy = self.section("accuracy") if "accuracy" in self._scene.sections_json else None
        return self._scene_accuracy

    def _grid_without_classes(self) -> bool:
        """The scene has a particles: section whose settings give no classes (the user left the grid to us)."""
        if not hasattr(self, "_no_classes"):
            self._no_classes = self._find_no_classes()
        return self._no_classes

    def _find_no_classes(self) -> bool:
        if self.grid() is None:
            return False
        part = self.section("particles")
        settings = (part or {}).get("settings") if isinstance(part, dict) else None
        return not (isinstance(settings, dict) and "classes" in settings)

    def _error_estimate(self, res: Result, **solver) -> "accuracy.ErrorEstimate":
        """The re-solves of :mod:`granuflow.accuracy` for ``res``: same output times and end time, tolerances
        divided by accuracy.TOLERANCE_FACTOR, grids refined by accuracy.REFINEMENTS (when there is a size grid)."""
        import time

        t0 = time.perf_counter()
        tight = {"rtol": max(res.rtol / accuracy.TOLERANCE_FACTOR, accuracy.MIN_RTOL),
                 "atol": res.atol / accuracy.TOLERANCE_FACTOR}
        common = {"t_end": float(res.t[-1]), "t_out": [float(t) for t in res.t], "warn": False,
                  **{k: v for k, v in solver.items() if v is not None}}
        tight_res = self.simulate(**common, **tight)
        refined, grid, notes = [], "", []
        g = self.grid()
        if g is not None:
            try:
                flowsheets = [self.refined(f) for f in accuracy.REFINEMENTS]
            except ConfigError as e:  # beyond the grid's limits (classes <= 2000): no discretization estimate
                notes.append(f"no grid refinement: {' '.join(str(e).split())}")
                flowsheets = []
            try:
                refined = [fs.simulate(**common, **tight) for fs in flowsheets]
            except _core.SolverError as e:  # the answer stands; only its grid error is not known
                notes.append(f"no grid refinement: a solve on a refined grid failed ({' '.join(str(e).split())})")
                refined, flowsheets = [], []
            key = "q" if g.get("grid") == "geometric" else "classes"
            if flowsheets:
                grid = f"particles.{key} " + ", ".join(str(x.grid()[key]) for x in [self] + flowsheets)
                for u in self._liquid_classes():  # a 2-D population's liquid axis, refined alike
                    grid += f"; {u}.liquid_classes " + ", ".join(str(x._liquid_classes()[u])
                                                                 for x in [self] + flowsheets)
        return accuracy.estimate(res, tight_res, refined, self.summary_keys(), grid, (res.rtol, tight["rtol"]),
                                 time.perf_counter() - t0, notes)

    def output_sensitivities(self, params: Sequence[str], *, t_end: float | None = None,
                             times: Sequence[float] | None = None):
        """Exact sensitivities of every reported output to ``params``: ``d output / d param`` as an array
        [time, param, output] (SI per SI) at ``times`` (default: the end time), from one forward-sensitivity solve
        (the units' outputs are evaluated with the states' sensitivities carried through)."""
        t_end = self.t_end if t_end is None else _end_time(t_end, "output_sensitivities()")
        times = [t_end] if times is None else _times(times, "output_sensitivities(): times")
        for i, t in enumerate(times):
            if not 0 <= t <= t_end * (1 + 1e-12):
                raise ConfigError(f"output_sensitivities(): times[{i}] = {t:g} s: expected 0 <= t <= t_end = "
                                  f"{t_end:g} s")
        if isinstance(params, str):
            raise ConfigError(f"output_sensitivities(): params = {short(params)}: expected a list of parameter names")
        from . import _calibration

        return _calibration.output_sensitivities(self._scene, t_end, times, list(params))

    def time_residual(self, repeats: int = 7, classes_local: bool = False) -> dict:
        """Median time of one residual and one Jacobian evaluation at the initial state (benchmarks);
        ``classes_local``: the Jacobian the class_local linear solver asks for (without the couplings between
        size classes)."""
        return self._scene.time_residual(repeats, classes_local=classes_local)

    def calibrate_raw(self, experiments: list, stages: list, options: dict, start: Mapping[str, float],
                      progress=None) -> dict:
        """The core's staged calibration on this flowsheet (use :func:`granuflow.calibration.calibrate`)."""
        from . import _calibration

        return _calibration.calibrate(self._scene, experiments, stages, options, dict(start), progress)

    def predict_raw(self, experiments: list, params: Mapping[str, float], options: dict) -> list:
        """The core's predictions of the experiments' observables (use :func:`granuflow.calibration.predict`)."""
        from . import _calibration

        return _calibration.predict(self._scene, experiments, dict(params), options)

    def diagram(self) -> "diagram.Diagram":  # noqa: F821 - imported when drawn
        """The flowsheet drawn by Graphviz: shown inline in a notebook; ``.save("fs.svg")`` writes it."""
        from .diagram import Diagram

        return Diagram(self)

    def __repr__(self) -> str:
        return f"<granuflow.Flowsheet {self.name!r}: {len(self.state_names)} states, {len(self.params)} parameters>"


def _with_grid_settings(text: str, settings: dict, label: str, section: tuple = ("particles",)) -> str:
    """The scene text with ``particles: settings:`` (or the ``settings:`` of another ``section``, e.g.
    ``("units", "granulator")``) holding ``settings``, all else as written (:func:`structure.splice_settings`)."""
    from . import structure

    return structure.splice_settings(text, section[-1], settings, label)


def _times(values, where: str) -> list[float]:
    """A list of times in s (numbers); ConfigError naming ``where`` otherwise."""
    if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, Iterable):
        raise ConfigError(f"{where} = {short(values)}: expected a list of times in s")
    values = list(values)
    for i, v in enumerate(values):
        if not is_number(v):
            raise ConfigError(f"{where}[{i}] = {short(v)}: expected a finite number (s)")
    return [float(v) for v in values]


def _end_time(value, where: str) -> float:
    """An end time: seconds or a string with a time unit, finite and > 0. ``where``: the call, e.g. "simulate()"."""
    t = parse_time(value, f"{where}: t_end")
    if not (math.isfinite(t) and t > 0):
        raise ConfigError(f"{where}: t_end = {t:g} s violates t_end > 0 (an end time in s, or with a time unit such "
                          "as '60 min')")
    return t


def sweep_batch_raw(flowsheets: Sequence[Flowsheet], *args) -> dict:
    """``_core.sweep_batch`` on ``flowsheets``, one thread each (never the same flowsheet twice;
    granuflow.sweep.batch)."""
    return _core.sweep_batch([f._scene for f in flowsheets], *args)


def load(path: str | os.PathLike) -> Flowsheet:
    """Load a scene file (YAML). Raises ConfigError naming the file, the key and what is allowed."""
    if not isinstance(path, (str, os.PathLike)):
        raise ConfigError(f"load({short(path)}): expected the path of a scene file (str)")
    check_regular(path, "scene file")  # a directory or a fifo where the scene should be: named, never read
    return Flowsheet(_core.load_scene(os.fspath(path)))


def load_text(text: str, label: str = "<text>") -> Flowsheet:
    """A flowsheet from the text of a scene file; ``label`` names it in messages (a file name)."""
    if not isinstance(text, (str, bytes)):
        raise ConfigError(f"{label}: the scene must be given as text (str), got {type(text).__name__}")
    return Flowsheet(_core.load_scene_text(text, label))
