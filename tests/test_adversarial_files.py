"""Adversarial rows for what comes from files and streams: model files, ``io.load``, chunk
sources, chunked and Dask fits (see ``adversarial.py`` for the machinery)."""
from __future__ import annotations

import copy
import io as _io
import json
import tempfile
import zipfile
from pathlib import Path

import dask.array as da
import h5py
import numpy as np

import discrepancy as dc
from adversarial import Case, check, circle, fast, params, raises, returns
from discrepancy import io
from discrepancy.distributed import fit_sources
from discrepancy.errors import (
    DataError,
    FeatureError,
    MissingFileError,
    ModelFileError,
    ParameterError,
    ResourceError,
    ShapeError,
    UnknownNameError,
)
from discrepancy.symbolic import symbol

T, X, XD = circle(300)
ROT = fast(prior=[symbol("x2"), 0 * symbol("x1")]).fit(X, 0.01, x_dot=XD)
DOC = ROT.to_state()
DIR = Path(tempfile.mkdtemp(prefix="adversarial-files-"))
FUNC_FILE = DIR / "functions.json"
fast(feature_library=dc.CustomLibrary(functions={"sq": np.square})).fit(X, 0.01, x_dot=X ** 2).save(
    FUNC_FILE)


def write(name: str, content) -> Path:
    """A file ``name`` in the suite's folder holding ``content`` (bytes or text)."""
    path = DIR / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return path


def npz(name, **arrays) -> Path:
    np.savez(DIR / name, **arrays)
    return DIR / name


def h5(name, **datasets) -> Path:
    with h5py.File(DIR / name, "w") as f:
        for key, value in datasets.items():
            if isinstance(value, tuple):  # a shape: declared, never written
                f.create_dataset(key, shape=value, dtype="f8")
            else:
                f[key] = value
    return DIR / name


def npy_member(header_shape, payload: bytes, dtype="<f8") -> bytes:
    buffer = _io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": dtype, "fortran_order": False,
                                                  "shape": header_shape})
    return buffer.getvalue() + payload


def zipped(name, members: dict) -> Path:
    with zipfile.ZipFile(DIR / name, "w") as z:
        for key, data in members.items():
            z.writestr(key, data)
    return DIR / name


def csv(name, text) -> Path:
    return write(name, text)


def load_doc(change=None, raw=None, **kw):
    """``load_model`` of the fitted model's file with ``change(doc)`` applied (or ``raw``
    text written instead)."""
    doc = copy.deepcopy(DOC)
    if change is not None:
        change(doc)
    path = write("model.json", raw if raw is not None else json.dumps(doc))
    return dc.load_model(path, **kw)


def setter(*keys_and_value):
    *keys, value = keys_and_value

    def change(doc):
        target = doc
        for k in keys[:-1]:
            target = target[k]
        target[keys[-1]] = value
    return change


def stream(chunks, t=0.01, **model):
    return fast(**model).fit(iter(chunks), t)


def on_dask(x, t=0.01, chunks=100, **kw):
    return fast().fit(da.from_array(x, chunks=(chunks, -1)), t, **kw)


ROTATION = fast().fit(X, 0.01, x_dot=XD).coef_


def same_model(m) -> bool:
    return np.allclose(m.coef_, ROTATION, atol=1e-9)


MAP = dc.DiscrepancyModel.from_prior([0.9 * symbol("x")], state_names=["x"], discrete_time=True)
MAP_FILE = DIR / "map.json"
MAP.save(MAP_FILE)


def edited_parameters(**edits):
    """The rotation model's file with ``parameters`` fields replaced, loaded."""
    doc = copy.deepcopy(DOC)
    doc["parameters"].update(edits)
    return dc.DiscrepancyModel.from_state(doc)


GOOD_CSV = "t,x1,x2\n" + "\n".join(f"{a},{b},{c}" for a, b, c in zip(T, X[:, 0], X[:, 1], strict=True))
FOLDER = DIR / "folder.csv"
FOLDER.mkdir()

CASES = [
    # --- model files
    Case("model file", "missing", lambda: dc.load_model(DIR / "nothing.json"), raises(MissingFileError, r"model file '.*nothing.json' does not exist")),
    Case("model file", "path None", lambda: dc.load_model(None), raises(ParameterError, r"model file must be a file name \(text or a pathlib.Path\); got None")),
    Case("model file", "path bytes", lambda: dc.load_model(b"m.json"), raises(ParameterError, r"model file must be a file name")),
    Case("model file", "a folder", lambda: dc.load_model(DIR), raises(ModelFileError, r"is a folder")),
    Case("model file", "empty", lambda: load_doc(raw=""), raises(ModelFileError, r"not valid JSON")),
    Case("model file", "truncated", lambda: load_doc(raw=json.dumps(DOC)[:200]), raises(ModelFileError, r"not valid JSON")),
    Case("model file", "not UTF-8", lambda: dc.load_model(write("latin.json", b"\xff\xfe{}")), raises(ModelFileError, r"not UTF-8")),
    Case("model file", "a JSON list", lambda: load_doc(raw="[1, 2]"), raises(ModelFileError, r"format is list")),
    Case("model file", "another format", lambda: load_doc(setter("format", "pysindy")), raises(ModelFileError, r"format is 'pysindy'")),
    Case("model file", "a newer version", lambda: load_doc(setter("version", 99)), raises(ModelFileError, r"version 99 is not one of")),
    Case("model file", "version as text", lambda: load_doc(setter("version", "2")), raises(ModelFileError, r"version '2'")),
    Case("model file", "an extra key", lambda: load_doc(setter("extra", 1)), raises(ModelFileError, r"needs exactly the keys")),
    Case("model file", "a missing key", lambda: load_doc(lambda d: d.pop("coefficients")), raises(ModelFileError, r"needs exactly the keys")),
    Case("model file", "state names not identifiers", lambda: load_doc(setter("state_names", ["x 1", "x2"])), raises(ModelFileError, r"state_names must be a list of distinct identifiers")),
    Case("model file", "repeated state names", lambda: load_doc(setter("state_names", ["x1", "x1"])), raises(ModelFileError, r"state_names must be a list of distinct")),
    Case("model file", "coefficient as text", lambda: load_doc(lambda d: d["coefficients"][0].__setitem__(0, "1")), raises(ModelFileError, r"coefficients must be 2 rows of 6 finite numbers")),
    Case("model file", "coefficient true", lambda: load_doc(lambda d: d["coefficients"][0].__setitem__(0, True)), raises(ModelFileError, r"coefficients must be")),
    Case("model file", "coefficient NaN", lambda: load_doc(raw=json.dumps(DOC).replace("[0.0,", "[NaN,", 1).replace("[0.0, ", "[NaN, ", 1)), raises(ModelFileError, r"coefficients must be|not valid JSON")),
    Case("model file", "coefficient 1e999", lambda: load_doc(raw=json.dumps(DOC).replace("0.0", "1e999", 1)), raises(ModelFileError, r"coefficients|finite")),
    Case("model file", "a coefficient row too short", lambda: load_doc(lambda d: d["coefficients"][1].pop()), raises(ModelFileError, r"coefficients must be 2 rows of 6")),
    Case("model file", "features empty", lambda: load_doc(setter("features", [])), raises(ModelFileError, r"features must be a non-empty list")),
    Case("model file", "feature calling code", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["sym", "__import__('os')"])), raises(ModelFileError, r"features\[1\].*identifier")),
    Case("model file", "feature of an unknown node", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["eval", "1"])), raises(ModelFileError, r"features\[1\]: unknown node 'eval'")),
    Case("model file", "feature of an unknown variable", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["sym", "y"])), raises(ModelFileError, r"features\[1\] uses variables outside")),
    Case("model file", "feature log(0)", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["fn", "log", ["num", 0, 1]])), raises(ModelFileError, r"features\[1\] is the constant zoo|not a finite real")),
    Case("model file", "feature sqrt(-1)", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["pow", ["num", -1, 1], ["num", 1, 2]])), raises(ModelFileError, r"features\[1\] is the constant I")),
    Case("model file", "feature float false", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["float", False])), raises(ModelFileError, r"float must be one finite number")),
    Case("model file", "feature rational over 0", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["num", 1, 0])), raises(ModelFileError, r"rational must be two integers")),
    Case("model file", "feature with a huge integer", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["num", 10**40, 1])), raises(ModelFileError, r"rational must be two integers of at most")),
    Case("model file", "feature exponent 1000", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["pow", ["sym", "x1"], ["num", 1000, 1]])), raises(ModelFileError, r"numeric exponents must be at most 64")),
    Case("model file", "feature nested 100 deep", lambda: load_doc(lambda d: d["features"].__setitem__(1, json.loads("[\"fn\", \"sin\", " * 100 + "[\"sym\", \"x1\"]" + "]" * 100))), raises(ModelFileError, r"nested too deeply")),
    Case("model file", "feature with an undeclared function", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["fn", "evil", ["sym", "x1"]])), raises(ModelFileError, r"function 'evil' is neither built in nor a declared")),
    Case("model file", "sin of two arguments", lambda: load_doc(lambda d: d["features"].__setitem__(1, ["fn", "sin", ["sym", "x1"], ["sym", "x2"]])), raises(ModelFileError, r"sin takes one argument, got 2")),
    Case("model file", "prior of the wrong kind", lambda: load_doc(setter("prior", {"kind": "pickle", "data": "..."})), raises(ModelFileError, r"prior must be null or an object with kind")),
    Case("model file", "prior with one expression", lambda: load_doc(lambda d: d["prior"]["expressions"].pop()), raises(ModelFileError, r"prior expressions must be a list of 2")),
    Case("model file", "callable prior not passed", lambda: load_doc(setter("prior", {"kind": "callable", "name": "f_m"})), raises(ParameterError, r"pass it: load_model\(path, prior=f_m\)")),
    Case("model file", "prior passed to plain SINDy", lambda: load_doc(setter("prior", None), prior=lambda x, u: x), raises(ParameterError, r"fitted without a prior")),
    Case("model file", "user function not passed", lambda: load_doc(setter("user_functions", ["sq"])), raises(ParameterError, r"numpy functions \['sq'\]")),
    Case("model file", "user function names not identifiers", lambda: load_doc(setter("user_functions", ["a b"])), raises(ModelFileError, r"user_functions must be a list of identifiers")),
    Case("model file", "optimizer with code", lambda: load_doc(setter("optimizer", {"name": "stlsq", "params": {"threshold": "__import__('os')"}})), raises(ModelFileError, r"optimizer: .*threshold")),
    Case("model file", "unknown optimizer", lambda: load_doc(setter("optimizer", {"name": "bogus", "params": {}})), raises(ModelFileError, r"optimizer: .*'bogus'")),
    Case("model file", "differentiation with an unknown option", lambda: load_doc(setter("differentiation_method", {"name": "finite_difference", "params": {"axis": 9}})), raises(ModelFileError, r"differentiation_method: .*no parameter 'axis'")),
    Case("model file", "fit record of text", lambda: load_doc(setter("fit", "yes")), raises(ModelFileError, r"fit must be")),
    Case("model file", "fit record nested 10 deep", lambda: load_doc(setter("fit", "differentiation_choice", json.loads("{\"a\": " * 10 + "1" + "}" * 10))), raises(ModelFileError, r"differentiation_choice must be an object")),
    Case("model file", "over 20 MiB", lambda: load_doc(raw=" " * (21 * 2**20)), raises(ModelFileError, r"more than the 20971520")),
    Case("model file", "a 10**6-digit integer", lambda: load_doc(raw="1" * 10**6), raises(ModelFileError, r"not a usable JSON document|not valid JSON|format")),
    Case("model file", "user function that raises", lambda: dc.load_model(FUNC_FILE, functions={"sq": lambda v: 1 / 0}).predict(X), raises(FeatureError, r"user function 'sq' raised ZeroDivisionError")),
    Case("model file", "user function not callable", lambda: dc.load_model(FUNC_FILE, functions={"sq": 3}), raises(ParameterError, r"functions must be None or a non-empty mapping of identifier names to callables")),
    Case("model file", "round trip", lambda: load_doc().predict(X), returns(lambda v: np.allclose(v, XD, atol=1e-9))),
    Case("model file", "a saved map stays a map", lambda: dc.load_model(MAP_FILE).simulate([1.0], 3).ravel(), returns(lambda v: np.allclose(v, [1.0, 0.9, 0.81], rtol=1e-15))),
    Case("model file", "discrete_time edited to text", lambda: edited_parameters(discrete_time="yes"), raises(ModelFileError, r"parameters.discrete_time must be a bool")),
    Case("model file", "constraints edited to a string", lambda: edited_parameters(constraints="x1"), raises(ModelFileError, r"parameters.constraints must be null or an object")),
    Case("model file", "state_names edited to code", lambda: edited_parameters(state_names=["os.system('x')", "x2"]), raises(ModelFileError, r"state_names must be identifiers")),
    Case("model file", "from_state of a list", lambda: dc.DiscrepancyModel.from_state([1]), raises(ModelFileError, r"format is list")),
    # --- io.load
    Case("io.load", "missing file", lambda: io.load(DIR / "nothing.csv"), raises(MissingFileError, r"data file '.*nothing.csv' does not exist")),
    Case("io.load", "path a number", lambda: io.load(42), raises(ParameterError, r"data file must be a file name \(text or a pathlib.Path\); got 42")),
    Case("io.load", "states a number", lambda: io.load(csv("good.csv", GOOD_CSV), states=3), raises(ParameterError, r"io.load: states must be None or a name or a non-empty list of names; got 3")),
    Case("io.load", "states an empty list", lambda: io.load(npz("good.npz", x=X, t=T), states=[]), raises(ParameterError, r"states must be")),
    Case("io.load", "time a list", lambda: io.load(npz("good.npz", x=X, t=T), time=["t"]), raises(ParameterError, r"io.load: time must be None or a name")),
    Case("io.load", "a folder named .csv", lambda: io.load(FOLDER), raises(DataError, r"folder.csv' is a folder, not a file")),
    Case("io.load", "unknown suffix", lambda: io.load(write("run.xlsx", "a")), raises(UnknownNameError, r"unknown file type '.xlsx'; valid suffixes")),
    Case("io.load", "empty CSV", lambda: io.load(csv("empty.csv", "")), raises(DataError, r"empty.csv: a CSV file needs a header row and data rows; it is empty")),
    Case("io.load", "CSV header only", lambda: io.load(csv("header.csv", "t,x1\n")), raises(DataError, r"header.csv: .* no data rows")),
    Case("io.load", "CSV with a word in a cell", lambda: io.load(csv("word.csv", "t,x1\n0,1\n0.1,abc\n")), raises(DataError, r"word.csv line 3, column 'x1': non-numeric value 'abc'")),
    Case("io.load", "CSV with an empty cell", lambda: io.load(csv("hole.csv", "t,x1\n0,1\n0.1,\n")), raises(DataError, r"hole.csv line 3, column 'x1': an empty cell")),
    Case("io.load", "CSV with an extra cell", lambda: io.load(csv("extra.csv", "t,x1\n0,1,5\n")), raises(DataError, r"extra.csv line 2: 3 cells, more than the header's 2")),
    Case("io.load", "CSV with a short row", lambda: io.load(csv("short.csv", "t,x1,x2\n0,1\n")), raises(DataError, r"short.csv line 2: 2 cells; the header has 3")),
    Case("io.load", "CSV with a repeated column", lambda: io.load(csv("dup.csv", "t,x,x\n0,1,2\n")), raises(DataError, r"names \['x'\] more than once")),
    Case("io.load", "CSV with an unnamed column", lambda: io.load(csv("noname.csv", "t,,x\n0,1,2\n")), raises(DataError, r"header column 2 has no name")),
    Case("io.load", "CSV not UTF-8", lambda: io.load(write("latin.csv", b"t,x\n0,\xff\xfe\n")), raises(DataError, r"latin.csv line \d+: not readable as UTF-8")),
    Case("io.load", "CSV with a NUL byte", lambda: io.load(write("nul.csv", b"t,x\n0,1\x00\n")), raises(DataError, r"nul.csv line \d+: not readable|nul.csv line 2")),
    Case("io.load", "CSV with inf", lambda: io.load(csv("inf.csv", "t,x1\n0,1\n0.1,inf\n")), raises(DataError, r"inf.csv states must be finite; found inf at row 1")),
    Case("io.load", "CSV with decreasing times", lambda: io.load(csv("back.csv", "t,x1\n0,1\n-1,2\n")), raises(DataError, r"back.csv column 't' must be strictly increasing")),
    Case("io.load", "CSV unknown state column", lambda: io.load(csv("cols.csv", "t,x1\n0,1\n"), states=["x9"]), raises(UnknownNameError, r"columns \['x9'\] not found")),
    Case("io.load", "CSV with a byte order mark", lambda: io.load(write("bom.csv", "\ufeff" + GOOD_CSV)), returns(lambda d: d.state_names == ["x1", "x2"] and np.allclose(d.t, T))),
    Case("io.load", "CSV round trip", lambda: io.load(csv("good.csv", GOOD_CSV)).x, returns(lambda x: np.allclose(x, X, atol=1e-12))),
    Case("io.load", "NPZ not a zip", lambda: io.load(write("junk.npz", b"not a zip")), raises(DataError, r"junk.npz is not a readable NPZ")),
    Case("io.load", "NPZ truncated", lambda: io.load(write("cut.npz", npz("whole.npz", x=X).read_bytes()[:300])), raises(DataError, r"cut.npz is not a readable NPZ|cut.npz: array")),
    Case("io.load", "NPZ header larger than its data", lambda: io.load(zipped("lie.npz", {"x.npy": npy_member((10**6, 10**5), b"\0" * 64)})), raises(DataError, r"lie.npz: array 'x' declares shape \(1000000, 100000\)")),
    Case("io.load", "NPZ of a huge real array", lambda: io.load(zipped("huge.npz", {"x.npy": npy_member((10**5, 10**5), b"")})), raises(DataError, r"huge.npz: array 'x' declares")),
    Case("io.load", "NPZ with a broken header", lambda: io.load(zipped("badhead.npz", {"x.npy": b"\x93NUMPY\x01\x00garbage"})), raises(DataError, r"badhead.npz: array 'x' has no valid .npy header")),
    Case("io.load", "NPZ of Python objects", lambda: io.load(zipped("obj.npz", {"x.npy": npy_member((2,), b"", "|O")})), raises(DataError, r"obj.npz: array 'x' is not numeric \(dtype object\)")),
    Case("io.load", "NPZ without x", lambda: io.load(npz("nox.npz", y=X)), raises(UnknownNameError, r"variable 'x' not found; the file has \['y'\]")),
    Case("io.load", "NPZ of strings", lambda: io.load(npz("text.npz", x=np.array(["a", "b"]))), raises(ShapeError, r"text.npz states must be a numeric array")),
    Case("io.load", "NPZ of complex numbers", lambda: io.load(npz("complex.npz", x=X + 1j)), raises(DataError, r"complex.npz states must be real")),
    Case("io.load", "NPZ of a 0-d array", lambda: io.load(npz("scalar.npz", x=np.float64(3))), raises(ShapeError, r"scalar.npz states must be 2-D")),
    Case("io.load", "NPZ with t of the wrong length", lambda: io.load(npz("tlen.npz", x=X, t=T[:5])), raises(ShapeError, r"variable 't' must be a step or a 1-D array of 300")),
    Case("io.load", "NPZ round trip", lambda: io.load(npz("good.npz", x=X, t=T, u=T)).u, returns(lambda u: np.array_equal(u, T[:, None]))),
    Case("io.load", "HDF5 not HDF5", lambda: io.load(write("junk.h5", b"\x89HDF\r\n\x1a\n" + b"x" * 100)), raises(DataError, r"junk.h5 is not a readable HDF5 file")),
    Case("io.load", "HDF5 with an unused 32 GB dataset", lambda: io.load(h5("unused.h5", x=X, big=(4 * 10**9,))).x, returns(lambda x: np.array_equal(x, X))),
    Case("io.load", "HDF5 whose x is 32 GB", lambda: io.load(h5("bigx.h5", x=(2 * 10**9, 2))), raises(ResourceError, r"reading array 'x' \(2000000000, 2\) of bigx.h5 would need 32 GB")),
    Case("io.load", "HDF5 x of strings", lambda: io.load(h5("strings.h5", x=np.array([b"a", b"b"]))), raises(DataError, r"strings.h5: array 'x' is not numeric")),
    Case("io.load", "HDF5 u with other rows", lambda: io.load(h5("rows.h5", x=X, u=T[:10])), raises(ShapeError, r"rows.h5 inputs must have 300 rows")),
    Case("io.load", "MAT not MATLAB", lambda: io.load(write("junk.mat", b"MATLAB? no")), raises(DataError, r"junk.mat is not a readable MATLAB file")),
    # --- chunked and streamed fits
    Case("stream", "chunks of 2 and 3 columns", lambda: stream([X[:150], np.c_[X[150:], X[150:, 0]]]), raises(ShapeError, r"chunk 1 of trajectory 0: x must have 2 columns")),
    Case("stream", "NaN in chunk 1", lambda: stream([X[:150], np.where(X[150:] > 0.99, np.nan, X[150:])]), raises(DataError, r"chunk 1 of trajectory 0: x must be finite; found nan at row \d+ of the chunk \(row \d+ of the trajectory")),
    Case("stream", "chunk with t, then without", lambda: stream([dc.Chunk(X[:150], t=T[:150]), dc.Chunk(X[150:])]), raises(ShapeError, r"chunk 1 of trajectory 0: chunk has no t, unlike the first")),
    Case("stream", "times going back across chunks", lambda: stream([dc.Chunk(X[:150], t=T[:150]), dc.Chunk(X[150:], t=T[:150])]), raises(DataError, r"chunk 1 of trajectory 0: t must be strictly increasing \(also across chunks\)")),
    Case("stream", "a chunk of text", lambda: stream([X[:150], "rows"]), raises(ShapeError, r"chunk 1 of trajectory 0: a chunk must be an array of x")),
    Case("stream", "a mapping without x", lambda: stream([{"y": X}]), raises(ShapeError, r"a chunk mapping needs key 'x'")),
    Case("stream", "no chunks", lambda: stream([]), raises(ShapeError, r"trajectory 0 of x has no rows")),
    Case("stream", "1-D chunk", lambda: stream([X[:, 0]]), raises(ShapeError, r"x must be 2-D \(rows, states\)")),
    Case("stream", "u beside chunks", lambda: fast().fit(iter([X]), 0.01, u=T), raises(ParameterError, r"give u and x_dot inside the chunks")),
    Case("stream", "per-row t beside chunks", lambda: stream([X], t=T), raises(ParameterError, r"with chunked x, t must be the time step")),
    Case("stream", "weights beside chunks", lambda: fast().fit(iter([X]), 0.01, sample_weight=np.ones(300)), raises(ParameterError, r"give sample weights inside the chunks")),
    Case("stream", "a global method", lambda: stream([X[:150], X[150:]], differentiation_method="spline"), raises(ParameterError, r"global differentiation method")),
    Case("stream", "negative weight in a chunk", lambda: stream([dc.Chunk(X[:150], weight=np.ones(150)), dc.Chunk(X[150:], weight=-np.ones(150))]), raises(DataError, r"chunk 1 of trajectory 0: weight must be >= 0; found -1.0 at row 150")),
    Case("stream", "chunks equal the in-memory fit", lambda: stream([dc.Chunk(X[:100], x_dot=XD[:100]), dc.Chunk(X[100:], x_dot=XD[100:])]), returns(same_model)),
    Case("stream", "weak form chosen from the first rows", lambda: dc.DiscrepancyModel(differentiation_method="weak").fit(iter([X[:170], X[170:]]), 0.01).coef_, returns(lambda c: np.allclose(c, dc.DiscrepancyModel(differentiation_method="weak").fit(X, 0.01).coef_, atol=1e-12))),
    Case("stream", "HDF5 source with chunk_size 0", lambda: dc.HDF5Source(h5("src.h5", x=X), chunk_size=0), raises(ParameterError, r"HDF5Source: chunk_size must be an integer >= 1; got 0")),
    Case("stream", "HDF5 source with chunk_size -5", lambda: dc.HDF5Source(h5("src.h5", x=X), chunk_size=-5), raises(ParameterError, r"chunk_size must be an integer >= 1; got -5")),
    Case("stream", "HDF5 source with chunk_size 2.5", lambda: dc.HDF5Source(h5("src.h5", x=X), chunk_size=2.5), raises(ParameterError, r"chunk_size must be an integer >= 1; got 2.5")),
    Case("stream", "HDF5 source with lengths 0", lambda: dc.HDF5Source(h5("src.h5", x=X), lengths=[0, 300]), raises(ParameterError, r"lengths must be")),
    Case("stream", "HDF5 source with lengths not adding up", lambda: list(dc.HDF5Source(h5("src.h5", x=X), lengths=[100, 100]).trajectories()), raises(ShapeError, r"lengths add up to 200 rows; the file has 300")),
    Case("stream", "HDF5 source of a missing file", lambda: dc.HDF5Source(DIR / "none.h5"), raises(MissingFileError, r"data file '.*none.h5' does not exist")),
    Case("stream", "HDF5 source of a corrupt file", lambda: dc.HDF5Source(write("bad.h5", b"nope")), raises(DataError, r"bad.h5 is not a readable HDF5 file")),
    Case("stream", "HDF5 source without the dataset", lambda: dc.HDF5Source(h5("src.h5", x=X), x="states"), raises(UnknownNameError, r"no dataset 'states' \(for x\)")),
    Case("stream", "HDF5 source x a group", lambda: dc.HDF5Source(h5("group.h5", **{"run/x": X}), x="run"), raises(UnknownNameError, r"'run' \(for x\) is a group, not a dataset; the file has: run/x")),
    Case("stream", "HDF5 source x one number", lambda: dc.HDF5Source(h5("one.h5", x=np.float64(3))), raises(ShapeError, r"dataset 'x' \(x\) holds one number")),
    Case("stream", "HDF5 source of a 1-D x", lambda: dc.HDF5Source(h5("flat.h5", x=T)), raises(ShapeError, r"dataset 'x' \(x\) has shape \(300,\)")),
    Case("stream", "HDF5 source paths a number", lambda: dc.HDF5Source(42), raises(ParameterError, r"paths must be a file, a folder or a non-empty list")),
    Case("stream", "NPZ files with x a list", lambda: dc.NPZFiles([npz("good.npz", x=X, t=T)], x=["x"]), raises(ParameterError, r"NPZFiles: x must be a name; got list")),
    Case("stream", "CSV files with x a number", lambda: dc.CSVFiles(csv("good.csv", GOOD_CSV), x=3), raises(ParameterError, r"CSVFiles: x must be a name or a non-empty list of names; got 3")),
    Case("stream", "HDF5 source with t a list", lambda: dc.HDF5Source(h5("src.h5", x=X), t=["t"]), raises(ParameterError, r"HDF5Source: t must be None or a name")),
    Case("stream", "NPZ files of an empty folder", lambda: dc.NPZFiles(DIR / "folder.csv"), raises(MissingFileError, r"holds no files matching '\*.npz'")),
    Case("stream", "NPZ files with a lying header", lambda: stream_source(dc.NPZFiles([zipped("lie2.npz", {"x.npy": npy_member((10**6, 10**5), b"")})])), raises(DataError, r"lie2.npz: array 'x' declares shape")),
    Case("stream", "CSV files with chunk_size 0", lambda: dc.CSVFiles(csv("good.csv", GOOD_CSV), x=["x1", "x2"], chunk_size=0), raises(ParameterError, r"CSVFiles: chunk_size must be an integer >= 1")),
    Case("stream", "CSV files with one_trajectory 'yes'", lambda: dc.CSVFiles(csv("good.csv", GOOD_CSV), x=["x1", "x2"], one_trajectory="yes"), raises(ParameterError, r"one_trajectory must be True or False")),
    Case("stream", "CSV files without the column", lambda: stream_source(dc.CSVFiles(csv("good.csv", GOOD_CSV), x=["x1", "x9"])), raises(UnknownNameError, r"no column 'x9' \(for x\)")),
    Case("stream", "HDF5 source equals the in-memory fit", lambda: stream_source(dc.HDF5Source(h5("src2.h5", x=X, xd=XD), x_dot="xd", chunk_size=77)), returns(same_model)),
    # --- Dask
    Case("dask", "fit_sources of a number", lambda: fit_sources(fast(), [42]), raises(ParameterError, r"sources\[0\] must be a ChunkSource")),
    Case("dask", "fit_sources of nothing", lambda: fit_sources(fast(), []), raises(ShapeError, r"sources must hold at least one ChunkSource")),
    Case("dask", "0 rows", lambda: on_dask(np.zeros((0, 2))), raises(ShapeError, r"x\[0\] has no rows")),
    Case("dask", "NaN named by row", lambda: on_dask(np.where(np.arange(300)[:, None] == 250, np.nan, X)), raises(DataError, r"dask array x\[0\]( rows \d+\.\.\d+)?: x must be finite; found nan at row \d+ of the chunk \(row 250 of the trajectory")),
    Case("dask", "1-D array", lambda: on_dask(T[:, None]).fit(da.from_array(T), 0.01), raises(ShapeError, r"x must be 2-D")),
    Case("dask", "u with other rows", lambda: on_dask(X, u=da.from_array(T[:10])), raises(ShapeError, r"u must be \(300, 1\) like x")),
    Case("dask", "per-row t", lambda: on_dask(X, t=T), raises(ParameterError, r"with chunked x, t must be the time step")),
    Case("dask", "a global method", lambda: dc.DiscrepancyModel(differentiation_method="spline").fit(da.from_array(X, chunks=(100, -1)), 0.01), raises(ParameterError, r"global method")),
    Case("dask", "weights", lambda: fast().fit(da.from_array(X), 0.01, sample_weight=np.ones(300)), raises(ParameterError, r"dask arrays take none")),
    Case("dask", "one-row blocks", lambda: on_dask(X, chunks=1, x_dot=da.from_array(XD, chunks=(1, -1))), returns(same_model)),
    Case("dask", "weak form on Dask", lambda: dc.DiscrepancyModel(differentiation_method="weak").fit(da.from_array(X, chunks=(70, -1)), 0.01).coef_, returns(lambda c: np.allclose(c, dc.DiscrepancyModel(differentiation_method="weak").fit(X, 0.01).coef_, atol=1e-12))),
]


def stream_source(source):
    return fast().fit(source, 0.01)


@params(CASES)
def test_case(case):
    check(case)
