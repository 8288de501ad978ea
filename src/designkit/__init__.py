"""designkit: symbolic design and verification of robot manipulator controllers.

The public API is re-exported here explicitly.  Names are resolved lazily (PEP 562) so that
``import designkit`` and ``designkit --help`` do not import CasADi, cvxpy or matplotlib.

Every user mistake raises a :class:`DesignkitError` (:class:`SpecError`, :class:`ModelError`,
:class:`OutputError`; see :mod:`designkit.errors`); anything else is a bug.

Examples
--------
>>> import designkit as dk
>>> loaded = dk.parse_spec('''
... name: demo
... plant: {kind: link, Km: 2.0, tau: 0.5}
... controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
... ''')
>>> design = dk.synthesize(loaded.spec)
>>> round(design.gains["K1"], 9), round(design.gains["K3"], 9)
(50.0, 100.0)
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    # spec and pipeline
    "load_spec": "designkit.schema.loader",
    "parse_spec": "designkit.schema.loader",
    "LoadedSpec": "designkit.schema.loader",
    "Spec": "designkit.schema.spec",
    "synthesize": "designkit.families",
    "Design": "designkit.synthesis.design",
    "LinearSystem": "designkit.models.linear_system",
    "run": "designkit.pipeline",
    "PipelineResult": "designkit.pipeline",
    "ComparisonResult": "designkit.pipeline",
    "ComparisonSpec": "designkit.schema.comparison",
    "Check": "designkit.verification.check",
    "simulate": "designkit.simulation.run",
    "build": "designkit.simulation.run",
    "Simulator": "designkit.simulation.run",
    "run_trials": "designkit.simulation.trials",
    "FAMILIES": "designkit.families",
    "family": "designkit.families",
    "Plant": "designkit.models.plant",
    "zoo_plant": "designkit.models.robot_plant",
    "chain_plant": "designkit.models.robot_plant",
    "RobotPlant": "designkit.models.robot_plant",
    "ElasticJointPlant": "designkit.models.elastic",
    "Gains": "designkit.synthesis.design",
    "SimulationResult": "designkit.simulation.result",
    "write_report": "designkit.report",
    "sweep": "designkit.sweep",
    "tune": "designkit.tuning",
    "TuneResult": "designkit.tuning",
    # models
    "LinkPlant": "designkit.models.link",
    "ChainDescription": "designkit.models.description",
    "LinkDescription": "designkit.models.description",
    "Robot": "designkit.models.robot",
    "robot_from_dh": "designkit.models.robot",
    "enclose": "designkit.bounds",
    "model_bound": "designkit.models.bounds",
    "robot": "designkit.models.robots",
    "robot_from_urdf": "designkit.models.urdf",
    # errors
    "DesignkitError": "designkit.errors",
    "SpecError": "designkit.errors",
    "ModelError": "designkit.errors",
    "OutputError": "designkit.errors",
    "NameNotFoundError": "designkit.errors",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'designkit' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
