"""pneumo from Python: load a netlist, simulate it, sweep its parameters.

    import pneumo
    net = pneumo.load("netlists/cushion_rig.yaml")
    net.parameters                      # name -> Parameter(name, value, unit, where), SI
    res = net.simulate(set={"z_EC": 0.1, "p_supply": "7 bar"})
    res.t, res["x"], res.units["p_EC"], res.events, res.stats, res.metrics
    study = pneumo.sweep(net, grid={"z_EC": "0.5:3:6"}, metrics=["t_cushion"], threads=2)
    study["t_cushion"]                  # one value a run, numpy array

Values are SI numbers, or strings with a unit ("7 bar") as in `pneumo
simulate --set`. Bad input raises NetlistError with the command line's
message (file:line:column, component, parameter); a run the solver cannot
finish raises SimulationError. The C++ work runs without the GIL.
"""

import itertools
import numbers
from collections import namedtuple

import numpy as np

from . import _core
from ._core import NetlistError

__version__ = _core.__version__
__all__ = ["load", "sweep", "components", "component", "Netlist", "Result", "SweepResult",
           "NetlistError", "SimulationError"]

Parameter = namedtuple("Parameter", "name value unit where")
Event = namedtuple("Event", "t component message tag")
Port = namedtuple("Port", "name domain description")
ComponentParameter = namedtuple("ComponentParameter", "name unit default range kind description")
Output = namedtuple("Output", "name unit description")


class SimulationError(RuntimeError):
    """The solver could not finish the run; `result` holds the rows computed so far, `t` where it stopped."""

    def __init__(self, message, result=None, t=None):
        super().__init__(message)
        self.result = result
        self.t = t


def _value_text(value):
    """A value as `pneumo simulate --set` reads it: SI number (all digits) or quantity text."""
    if isinstance(value, str):
        return value
    return repr(float(value))


def _assignments(values):
    return [f"{name}={_value_text(v)}" for name, v in (values or {}).items()]


def _pandas():
    try:
        import pandas
    except ImportError as e:
        raise ImportError("to_pandas() needs pandas (apt-get install python3-pandas)") from e
    return pandas


class Result:
    """One run: `t` and each output as a numpy array (`res["x"]`), SI units in `units`,
    events (Event(t, component, message, tag)), solver statistics and the netlist's metrics."""

    def __init__(self, raw):
        self.names = list(raw["names"])
        self.units = dict(zip(self.names, raw["units"]))
        self._data = raw["data"]  # (columns, rows); each column a contiguous view
        self._index = {n: i for i, n in enumerate(self.names)}
        self.events = [Event(*e) for e in raw["events"]]
        self.stats = dict(raw["stats"])
        self.metrics = dict(zip(raw["metric_names"], raw["metric_values"]))
        self.metric_units = dict(zip(raw["metric_names"], raw["metric_units"]))

    @property
    def t(self):
        return self["t"]

    def __getitem__(self, name):
        try:
            return self._data[self._index[name]]
        except KeyError:
            raise KeyError(f"no output '{name}'; the outputs are {', '.join(self.names)}") from None

    def __contains__(self, name):
        return name in self._index

    def __len__(self):
        return self._data.shape[1]

    def events_of(self, component=None, tag=None):
        """Events of a component and/or with a tag (the COMPONENT.TAG metrics name)."""
        return [e for e in self.events
                if (component is None or e.component == component) and (tag is None or e.tag == tag)]

    def to_pandas(self):
        """A DataFrame indexed by t, one column per output (needs pandas)."""
        pd = _pandas()
        return pd.DataFrame({n: self[n] for n in self.names[1:]}, index=pd.Index(self.t, name="t"))

    def __repr__(self):
        return f"<pneumo.Result {len(self)} rows of {', '.join(self.names)}; {len(self.events)} events>"


class Netlist:
    """A loaded netlist. `parameters`: its top-level parameters (SI values and units)."""

    def __init__(self, path):
        self._core = _core.Netlist(str(path))

    @property
    def file(self):
        return self._core.file

    @property
    def parameters(self):
        return {p[0]: Parameter(*p) for p in self._core.parameters}

    @property
    def outputs(self):
        return list(self._core.outputs)

    @property
    def metrics(self):
        return list(self._core.metrics)

    def simulate(self, set=None):
        """Run the netlist with top-level parameters overridden by `set` (name -> value)."""
        raw = self._core.simulate(_assignments(set))
        result = Result(raw)
        if not raw["ok"]:
            raise SimulationError(f"simulation of {self.file} failed: {raw['message']}", result, raw["t_reached"])
        return result

    def __repr__(self):
        return f"<pneumo.Netlist {self.file}>"


def load(path):
    """Read a netlist (YAML) and its plugins; raises NetlistError for bad input."""
    return Netlist(path)


class SweepResult:
    """Runs of a sweep: each parameter and metric as a numpy array over the runs
    (`study["t_cushion"]`, SI, NaN where a run failed or a metric is undefined),
    `units`, `ok`, `steps` and the `reasons` runs failed."""

    def __init__(self, raw):
        self.parameters = {name: values for name, _, values in raw["parameters"]}
        self.metrics = {name: values for name, _, values in raw["metrics"]}
        self.units = {name: unit for name, unit, _ in raw["parameters"] + raw["metrics"]}
        self.ok = raw["ok"]
        self.steps = raw["steps"]
        self.reasons = list(raw["reasons"])

    def __getitem__(self, name):
        if name in self.parameters:
            return self.parameters[name]
        if name in self.metrics:
            return self.metrics[name]
        raise KeyError(f"no parameter or metric '{name}' in this sweep")

    def __len__(self):
        return len(self.ok)

    def to_pandas(self):
        """A DataFrame, one row a run (needs pandas)."""
        pd = _pandas()
        columns = dict(self.parameters)
        columns.update(self.metrics)
        columns.update(ok=self.ok, steps=self.steps, reason=self.reasons)
        return pd.DataFrame(columns)

    def __repr__(self):
        return (f"<pneumo.SweepResult {len(self)} runs ({int(np.count_nonzero(~self.ok))} failed) of "
                f"{', '.join(self.parameters)} -> {', '.join(self.metrics)}>")


def _count(name, count):
    """A grid's COUNT: a whole number however it is typed (3, 3.0, numpy.int64(3))."""
    if isinstance(count, (bool, np.bool_)) or not isinstance(count, (numbers.Integral, numbers.Real)):
        raise ValueError(f"pneumo.sweep: grid {name!r}: COUNT must be a whole number, not {count!r}")
    if isinstance(count, numbers.Integral):
        return int(count)
    if not (np.isfinite(count) and float(count).is_integer()):
        raise ValueError(f"pneumo.sweep: grid {name!r}: COUNT must be a whole number, not {count!r}")
    return int(count)


def _rows(samples, names):
    """The runs of a samples array: one row per run, one column per name; a
    matrix the other way round is refused rather than silently reshaped."""
    a = np.asarray(samples, dtype=float)
    if a.ndim == 1 and len(names) == 1:
        a = a.reshape(-1, 1)
    if a.ndim != 2 or a.shape[1] != len(names):
        hint = " (it looks transposed: pass samples.T)" if a.ndim == 2 and a.shape[0] == len(names) else ""
        raise ValueError(f"pneumo.sweep: samples has shape {a.shape}; it needs one row per run and one column "
                         f"per name, {len(names)} columns for names={names}{hint}")
    return a.tolist()


def _axis(net, name, spec):
    """One grid axis in SI: "FROM:TO:COUNT" or (FROM, TO, COUNT) as `pneumo sweep --grid`, or the values."""
    if isinstance(spec, tuple) and len(spec) == 3:
        spec = f"{_value_text(spec[0])}:{_value_text(spec[1])}:{_count(name, spec[2])}"
    if isinstance(spec, str):
        return _core.grid_axis(net._core, name, spec)
    return [float(v) for v in np.asarray(spec, dtype=float).ravel()]


def sweep(net, grid=None, samples=None, names=None, metrics=None, threads=1, set=None):
    """Run `net` over a full factorial `grid` (name -> "FROM:TO:COUNT", (FROM, TO, COUNT)
    or a list of SI values; the last name varies fastest, as `pneumo sweep --grid`) or over
    `samples` (name -> array, or a 2-D array with one column per entry of `names`), on
    `threads` threads. `metrics`: names of the netlist's metrics (default all). Failing runs
    do not raise: their `ok` is False and `reasons` says why."""
    if (grid is None) == (samples is None):
        raise ValueError("pneumo.sweep: give either grid= or samples=")
    if grid is not None:
        names = list(grid)
        axes = [_axis(net, name, grid[name]) for name in names]
        rows = [list(r) for r in itertools.product(*axes)]
    elif isinstance(samples, dict):
        names = list(samples)
        rows = np.column_stack([np.asarray(samples[n], dtype=float) for n in names]).tolist()
    else:
        if names is None:
            raise ValueError("pneumo.sweep: a samples array needs names= (one per column)")
        names = list(names)
        rows = _rows(samples, names)
    raw = _core.sweep(net._core, names, rows, list(metrics or []), _assignments(set), int(threads))
    return SweepResult(raw)


def components():
    """The built-in component types."""
    return list(_core.component_types())


class Component:
    """A component type: ports, parameters (unit, default, valid range) and outputs."""

    def __init__(self, raw):
        self.type = raw["type"]
        self.description = raw["description"]
        self.ports = [Port(*p) for p in raw["ports"]]
        self.parameters = [ComponentParameter(*p) for p in raw["parameters"]]
        self.outputs = [Output(*o) for o in raw["outputs"]]

    def __repr__(self):
        return f"<pneumo.Component {self.type}: {self.description}>"


def component(type):
    """A built-in component type's description (KeyError for an unknown type)."""
    return Component(_core.component(type))
