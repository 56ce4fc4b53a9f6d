"""The scenario layer: both scenario file formats -> typed objects (numpy, meshes' parameter
dataclasses and the transient model; no gmsh, no dolfinx).

* ``liftoff transient`` files (two bodies, contacts, forces): :func:`load_twobody` ->
  :class:`TwoBodyScenario` holding a :class:`liftoff.transient.TransientProblem`;
* ``liftoff run`` files (models, posts, engines, effects, cases): :func:`load_scenario`
  -> :class:`Scenario` of :class:`Case` objects with a :class:`ModelConfig`; with
  ``kind = "barge"`` (the barge impact, docs/barge.md) :func:`load_barge` ->
  :class:`BargeScenario` of :class:`BargeCase` objects (:func:`scenario_kind` tells which);
* the sections both share (time, forces, gravity, contact law, softening, control, cryo)
  in :mod:`.sections`, the value checks and the one error wording
  (``file: key.path: what``) in :mod:`.values`, file reading in :mod:`.files`.
"""

from liftoff.core.lazy import lazy_exports

_EXPORTS = {
    "Where": ".values",
    "parse_toml": ".files",
    "read_toml": ".files",
    "read_csv_table": ".files",
    "TimeSpan": ".sections",
    "Force": ".sections",
    "at_point": ".sections",
    "Softening": ".sections",
    "Control": ".sections",
    "Cryo": ".sections",
    "ComponentModel": ".model",
    "ModelConfig": ".model",
    "SystemModel": ".model",
    "Case": ".scenario",
    "Engine": ".scenario",
    "OutputFlags": ".scenario",
    "Post": ".scenario",
    "RecoveryPoints": ".scenario",
    "Scenario": ".scenario",
    "default_text": ".scenario",
    "load_scenario": ".scenario",
    "merge": ".extends",
    "read_scenario": ".extends",
    "EXAMPLES": ".extends",
    "example_text": ".extends",
    "parse_scenario": ".scenario",
    "BargeScenario": ".barge",
    "BargeCase": ".barge",
    "load_barge": ".barge",
    "scenario_kind": ".barge",
    "TwoBodyScenario": ".twobody",
    "load_twobody": ".twobody",
    "parse_twobody": ".twobody",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
