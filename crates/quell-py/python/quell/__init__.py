"""quell: direct adaptive output-feedback control of unstable MIMO linear plants with distinct
input delays and unknown multi-harmonic references and disturbances.

It implements C. V. Tu and N. Dudarenko, "Direct adaptive output-feedback control for unstable
linear multidimensional systems with distinct input delays" (2026); equation numbers in the
docstrings refer to that paper.

>>> import quell
>>> scenario = quell.paper_example()                 # Section VIII
>>> result = quell.simulate(scenario)                # the continuous loop, 100 s
>>> result.outcome
{'status': 'completed'}
"""

from ._errors import ControllerError, DesignError, ExportError, QuellError, ScenarioError, SimulationError
from ._study import StudyResult
from ._tune import TuneResult
from ._quell import (
    Controller,
    Design,
    Plant,
    RunSpec,
    Scenario,
    SimResult,
    Study,
    __version__,
    auto_design,
    design,
    export,
    paper_example,
    place,
    run_one,
    simulate,
    sweep,
    sweep_runs,
    tune,
)

__all__ = [
    "Controller",
    "ControllerError",
    "Design",
    "DesignError",
    "ExportError",
    "Plant",
    "QuellError",
    "RunSpec",
    "Scenario",
    "ScenarioError",
    "SimResult",
    "SimulationError",
    "Study",
    "StudyResult",
    "TuneResult",
    "__version__",
    "auto_design",
    "design",
    "export",
    "paper_example",
    "place",
    "run_one",
    "simulate",
    "sweep",
    "sweep_runs",
    "tune",
]
