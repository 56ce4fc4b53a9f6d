"""``make setup`` compiles the transient kernel (transient/warm.py). A run without contact
laws must use march's specialisation with ``laws`` None, whose laws branches numba prunes
before typing (the reason the first reference run compiles in about half the time)."""
import pytest
from numba import types

from liftoff.transient import warm
from liftoff.transient.kernel import march


def test_reference_path_is_the_pruned_specialisation():
    assert warm.warm("reference") >= 0.0
    laws_types = [sig[-1] for sig in march.signatures]
    assert any(t == types.none or isinstance(t, types.Omitted) for t in laws_types), laws_types


def test_unknown_path_is_refused():
    with pytest.raises(ValueError, match="reference"):
        warm.warm("fast")
