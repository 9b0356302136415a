"""Large tables held by reference (bsdfkit.models.tables.TableRef): cheap ==, hash, repr, pickle;
content-addressed; read once; a changed file is refused."""
import pickle

import numpy as np
import pytest

from bsdfkit.models.tables import TableRef


def test_table_ref(tmp_path):
    a, b = tmp_path / "a.npy", tmp_path / "b.npy"
    np.save(a, np.arange(1000.0))
    np.save(b, np.arange(1000.0))
    ra, rb = TableRef(a), TableRef(str(b))
    assert ra == rb and hash(ra) == hash(rb)          # same content, different paths
    assert eval(repr(ra), {"TableRef": TableRef}) == ra
    assert pickle.loads(pickle.dumps(ra)) == ra and len(pickle.dumps(ra)) < 300
    calls = []

    def reader(p):
        calls.append(p)
        return np.load(p)
    np.testing.assert_array_equal(ra.load(reader), np.arange(1000.0))
    assert ra.load(reader) is ra.load(reader) and len(calls) == 1    # read once per process
    np.save(b, np.zeros(3))
    assert TableRef(b) != rb
    with pytest.raises(OSError, match="changed since it was referenced"):
        TableRef(str(b), digest=rb.digest).load(lambda p: None)
    with pytest.raises(OSError, match="no such table file"):
        TableRef(tmp_path / "missing.npy")
    with pytest.raises(ValueError, match="digest"):
        TableRef(a, digest="md5:0")
    with pytest.raises(AttributeError):
        ra.path = "x"
