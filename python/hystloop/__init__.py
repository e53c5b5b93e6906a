"""hystloop for Python: the project's hysteresis models, their identification and its LCM logs.

The C++ code of hystloop-model, hystloop-identify and hystloop-report (hystloop._core), with numpy
arrays in and out, in SI units (s, V, m):

    import hystloop
    m = hystloop.Model("mem", c1=5e-9, c2=1.7e-12, c3=1.2)   # hystloop.models(), hystloop.model_info("mem")
    y = m.forward(u)                                          # u [V] -> y [m]
    u_ff = m.inverse(y_ref)                                   # y_ref [m] -> u [V]
    fit = hystloop.identify(t, u, y, model="auto")           # fit.model, fit.params, fit.ranking
    ban = hystloop.identify_banning("series.lcmlog")         # ban.a, ban.b, ban.alpha, ban.k, ban.c, ban.yaml
    st = hystloop.identify_stage(u, y, period_samples=2000, periods=4)  # st["poles_hz"], st["delay_s"], Bode data
    log = hystloop.read_log("run.lcmlog", axis=0)            # log["HX_SENSOR"]["y_m"], .units
    exp = hystloop.read_export("run.h5")                     # hystloop-export's .h5/.mat, as read_log
    rig = hystloop.Rig()                                      # a running rig (ttl=0: this host)
    rig.arm(); rig.set_trajectory("cosine", amplitude_m=1e-6); ticks = rig.record(10.0)

Axes are numbered as on the wire: x = 0, y = 1, z = 2 (hystloop.AXES).
"""

from ._core import (
    BanningResult,
    Channel,
    FitError,
    IdentifyResult,
    Log,
    Model,
    ParameterError,
    RankedModel,
    Rig,
    RigError,
    identify,
    identify_banning,
    identify_stage,
    model_info,
    models,
    read_log,
)
from .export import Export, ExportChannel, read_export

AXES = {"x": 0, "y": 1, "z": 2}


def _blocks(self, timeout=1.0, count=None):
    """The rig's sensor blocks as they come, each as Rig.record() gives its ticks: a live view for a
    plot (blocks arriving between two steps of the loop may be skipped; record() keeps every tick).
    Ends after `timeout` [s] without a block, or after `count` blocks."""
    n = 0
    while count is None or n < count:
        block = self.next_block(timeout)
        if block is None:
            return
        yield block
        n += 1


Rig.blocks = _blocks

__all__ = [
    "AXES",
    "BanningResult",
    "Channel",
    "Export",
    "ExportChannel",
    "FitError",
    "IdentifyResult",
    "Log",
    "Model",
    "ParameterError",
    "RankedModel",
    "Rig",
    "RigError",
    "identify",
    "identify_banning",
    "identify_stage",
    "model_info",
    "models",
    "read_export",
    "read_log",
]
