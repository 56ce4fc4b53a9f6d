"""The ground floor of liftoff (numpy only; imports nothing else of the project):
errors, files (atomic writes, self-describing records), DOF labels and the named-point
rule, and rigid-body kinematics with the mass properties of a 6x6 rigid-body mass."""
from .errors import ConvergenceError, InputError, ResourceError
from .labels import COMPONENTS, TRANSLATIONS, is_named_point, named_points, point_labels, points_labels, split_label
from .records import Dataset, Record, atomic_path, read_record, write_record, write_text
from .rigid import MassProperties, cg_mass, dof_rb, nodal_rb, point_rb, rb_rows, shift_rb, skew

__all__ = ["InputError", "ConvergenceError", "ResourceError", "COMPONENTS", "TRANSLATIONS", "split_label", "point_labels",
           "points_labels", "is_named_point", "named_points", "atomic_path", "write_text", "Dataset", "Record",
           "write_record", "read_record", "MassProperties", "cg_mass", "skew", "dof_rb", "point_rb",
           "nodal_rb", "rb_rows", "shift_rb"]
