"""Measured materials: MERL ``.binary`` tables (:class:`MERL`) and RGL tensor files
(:class:`Measured`, Dupuy & Jakob 2018). C++ cores: cpp/include/bsdfkit/bxdfs/merl.h and measured.h.

Files are read and validated here, with numpy: every failure is a ``ValueError`` (bad content)
or an ``OSError`` (missing file, a directory, unreadable) whose message names the file and the
field; nothing is allocated from a size declared in a file before that size has been checked
against the file's actual length. Loaded tables are immutable and shared between the models
that use them (one C++ table per file content and knob); a model holds the absolute path and
the SHA-256 digest of the file's bytes, and pickles by (path, digest): unpickling reloads the
file and refuses it if its content changed.
"""
from __future__ import annotations

import collections
import hashlib
import os
import threading
import weakref

import numpy as np

from .. import _core
from .base import BxDF
from .registry import KnobDecl

__all__ = ["example_dir", "MERL", "MERL_SCALE", "MERL_DIMS", "read_merl", "parse_merl", "merl_uplift_coefficients", "Measured", "read_tensor", "write_tensor", "parse_tensor",
           "tensor_bytes", "validate_measured"]

#: MERL's channel scale factors (RED_SCALE, GREEN_SCALE, BLUE_SCALE of BRDFRead.cpp): stored
#: values times these are the BRDF in 1/sr.
MERL_SCALE = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
#: (theta_h bins, theta_d bins, phi_d bins): the only table shape MERL files have.
MERL_DIMS = (90, 90, 180)
#: Sampler resolution: incidence-angle tables and azimuth columns (rows are MERL's 90 theta_h bins).
MERL_SAMPLER_K, MERL_SAMPLER_NPHI = 32, 64
#: float32's largest value: the C++ tables keep a float32 copy of their values for float32
#: evaluation (merl.h v32; the measured warps), where a larger value became inf and float32
#: calls returned 0 or inf without an error. File values are checked against it (MERL's are
#: then divided by ~1500: headroom for the float32 arithmetic on them).
_F32_MAX = float(np.finfo(np.float32).max)
_MEASURED_MIN_COS = 1e-2  # bxdfs/measured.h measured::kMinCos: f = f cos / max(cos_i, kMinCos)

_INTERPOLATION = {"nearest": "MERLNearest", "linear": "MERLLinear"}
_LOCK = threading.Lock()
_TABLES: "collections.OrderedDict" = collections.OrderedDict()   # (digest, linear) -> _core.MERLTable
_MAX_TABLES = 6


def example_dir() -> str:
    """Where ``from_metal`` writes its files: ``$BSDFKIT_CACHE`` or ``<tmp>/bsdfkit-<user>``/measured."""
    import getpass
    import tempfile
    try:
        user = getpass.getuser()
    except Exception:  # pragma: no cover - no user name on some containers
        user = "user"
    root = os.environ.get("BSDFKIT_CACHE") or os.path.join(tempfile.gettempdir(), f"bsdfkit-{user}")
    d = os.path.join(root, "measured")
    os.makedirs(d, exist_ok=True)
    return d


def _example_file(stem: str, ext: str, write) -> str:
    """A cached example file: written once (atomically) by ``write(path)``."""
    path = os.path.join(example_dir(), f"{stem}{ext}")
    if not os.path.isfile(path):
        tmp = f"{path}.{os.getpid()}.{threading.get_ident()}.tmp"
        write(tmp)
        os.replace(tmp, path)
    return path


def _read_bytes(path, what: str, limit: int | None = None) -> tuple[str, bytes, int]:
    """(absolute path, content, size in bytes) of a regular file, with OSErrors that name it.
    A device, FIFO or socket is refused before it is opened (``/dev/zero`` was read until memory
    ran out, a FIFO without a writer blocked forever). ``limit``: read at most that many bytes
    (the size returned is the file's)."""
    try:
        p = os.fspath(path)
    except TypeError:
        raise TypeError(f"path: expected a str or os.PathLike, got {type(path).__name__}") from None
    if not isinstance(p, str):
        p = os.fsdecode(p)
    if "\x00" in p:
        raise ValueError(f"path: contains a NUL character: {p!r}")
    ap = os.path.abspath(p)
    if os.path.isdir(ap):
        raise IsADirectoryError(f"{ap}: is a directory, not a {what} file")
    try:
        with open(ap, "rb", opener=_regular_file_opener) as fh:
            size = os.fstat(fh.fileno()).st_size
            data = fh.read() if limit is None else fh.read(limit)
    except FileNotFoundError:
        raise FileNotFoundError(f"{ap}: no such {what} file") from None
    except _NotRegularFile as e:
        raise OSError(f"{ap}: {e}, not a {what} file") from None
    except OSError as e:
        raise OSError(f"{ap}: cannot read the {what} file ({e.strerror or e})") from None
    return ap, data, size


class _NotRegularFile(OSError):
    pass


def _regular_file_opener(path, flags):
    """``open``'s opener: opens without blocking (a FIFO would wait for a writer) and refuses
    anything but a regular file (a device such as /dev/zero never ends)."""
    import stat
    fd = os.open(path, flags | getattr(os, "O_NONBLOCK", 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = ("a directory" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else "a character device" if stat.S_ISCHR(mode)
                    else "a block device" if stat.S_ISBLK(mode) else "a socket" if stat.S_ISSOCK(mode) else "special")
            raise _NotRegularFile(f"not a regular file but {kind}")
        if hasattr(os, "O_NONBLOCK"):
            os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd


def read_merl(path) -> tuple[np.ndarray, np.ndarray, str, str]:
    """Read a MERL ``.binary`` file.

    Returns ``(values, measured, abspath, digest)``: ``values`` float64 (90, 90, 180, 3) BRDF in
    1/sr (channel scales applied; not-measured bins set to 0), ``measured`` bool (90, 90, 180, 3)
    (False where the file holds a negative value), the absolute path and the SHA-256 of the bytes.

    Format (MERL BRDFRead.cpp): 3 int32 (90, 90, 180), then 3 x 90 x 90 x 180 float64,
    channel-planar (all red, then green, then blue), C order [theta_h][theta_d][phi_d],
    little-endian. Raises ValueError naming the file and the field for a short header, other
    dimensions, a payload of the wrong length, NaN/infinite values, or values beyond float32's
    max 3.4e38 (the table is evaluated in float32 too). Negative values ("not measured") of any
    size are accepted.
    """
    n = 12 + 24 * int(np.prod(MERL_DIMS))
    ap, data, size = _read_bytes(path, "MERL", limit=n + 1)   # a longer file is not read whole
    if size != len(data):
        parse_merl(data[:12], ap, check_size=False)            # the header's error first, if any
        raise ValueError(f"{ap}: values: expected {n - 12} bytes of float64 after the header, got {size - 12}")
    return parse_merl(data, ap)


def parse_merl(data: bytes, ap: str = "<bytes>", *, check_size: bool = True) -> tuple[np.ndarray, np.ndarray, str, str]:
    """:func:`read_merl` on the bytes of a file (``ap`` names it in the messages)."""
    if len(data) < 12:
        raise ValueError(f"{ap}: dims: truncated header ({len(data)} bytes; a MERL file starts with 3 int32)")
    dims = tuple(int(d) for d in np.frombuffer(data, "<i4", 3))
    if dims != MERL_DIMS:
        raise ValueError(f"{ap}: dims: expected {MERL_DIMS} (theta_h, theta_d, phi_d), got {dims}")
    if not check_size:
        return None
    n = 3 * int(np.prod(MERL_DIMS))
    if len(data) != 12 + 8 * n:
        raise ValueError(f"{ap}: values: expected {8 * n} bytes of float64 after the header, got {len(data) - 12}")
    raw = np.frombuffer(data, "<f8", n, offset=12).reshape((3,) + MERL_DIMS)
    if not np.all(np.isfinite(raw)):
        bad = np.argwhere(~np.isfinite(raw))[0]
        raise ValueError(f"{ap}: values: non-finite value at (channel, theta_h, theta_d, phi_d) = {tuple(int(b) for b in bad)}")
    if np.any(raw > _F32_MAX):
        bad = tuple(int(b) for b in np.argwhere(raw > _F32_MAX)[0])
        raise ValueError(f"{ap}: values: {raw[bad]:.9g} at (channel, theta_h, theta_d, phi_d) = {bad} exceeds "
                         f"float32's max {_F32_MAX:.9g} (the table is evaluated in float32 too)")
    measured = np.moveaxis(raw >= 0, 0, -1)
    values = np.moveaxis(raw, 0, -1) * np.asarray(MERL_SCALE)
    values = np.where(measured, values, 0.0)
    return values, measured, ap, hashlib.sha256(data).hexdigest()


def _merl_table(digest: str, linear: bool, values=None):
    key = (digest, linear)
    with _LOCK:
        t = _TABLES.get(key)
        if t is not None:
            _TABLES.move_to_end(key)
            return t
    if values is None:
        return None
    t = _core.MERLTable(np.ascontiguousarray(values), MERL_SAMPLER_K, MERL_SAMPLER_NPHI, linear)
    with _LOCK:
        _TABLES[key] = t
        while len(_TABLES) > _MAX_TABLES:
            _TABLES.popitem(last=False)
    return t


_SPECTRAL_TABLES: "collections.OrderedDict" = collections.OrderedDict()   # digest -> _core.MERLSpectralTable


def merl_uplift_coefficients(values: np.ndarray, chunk: int = 1 << 18) -> np.ndarray:
    """pbrt-v4's ``RGBUnboundedSpectrum`` of every MERL bin: float32 (..., 4) = (c0, c1, c2, scale)
    with value(lambda) = scale * s(c0 lambda^2 + c1 lambda + c2) (lambda in nm, s the Jakob &
    Hanika 2019 sigmoid), scale = 2 max(rgb), the coefficients of rgb / scale from the sRGB table
    (:func:`bsdfkit.spectral.uplift.rgb_coefficients`, the table lookup as pbrt-v4, no polish).
    values: (..., 3) RGB >= 0 (a zero bin gets scale 0: the spectrum 0)."""
    from ..spectral import uplift
    v = np.asarray(values, np.float64)
    flat = v.reshape(-1, 3)
    out = np.empty((flat.shape[0], 4), np.float32)
    for i in range(0, flat.shape[0], chunk):
        c, scale = uplift.rgb_coefficients(flat[i:i + chunk], "unbounded")
        out[i:i + chunk, :3] = c
        out[i:i + chunk, 3] = scale
    return out.reshape(v.shape[:-1] + (4,))


def _merl_spectral_table(digest: str, table):
    """The uplifted bins of a MERL table (one per file content, shared; 16 bytes per bin)."""
    with _LOCK:
        t = _SPECTRAL_TABLES.get(digest)
        if t is not None:
            _SPECTRAL_TABLES.move_to_end(digest)
            return t
    t = _core.MERLSpectralTable(merl_uplift_coefficients(table.values()))
    with _LOCK:
        _SPECTRAL_TABLES[digest] = t
        while len(_SPECTRAL_TABLES) > 2:
            _SPECTRAL_TABLES.popitem(last=False)
    return t


class MERL(BxDF):
    """A MERL measured isotropic BRDF table (Matusik et al. 2003, ``.binary``), evaluated and
    importance-sampled.

    path: the ``.binary`` file (see :func:`read_merl` for the format and the checks).
    interpolation: ``"nearest"`` (MERL's own lookup: the value of the bin the angles fall in) or
    ``"linear"`` (trilinear between bin centres in (sqrt(theta_h), theta_d, phi_d); smoother, ~2x
    the cost of a lookup). digest: optional SHA-256 of the file; if given, the file must match.

    Coordinates: Rusinkiewicz half/difference angles, with MERL's non-linear theta_h index
    sqrt(theta_h / (pi/2)) * 90 and the reciprocity fold phi_d -> phi_d + pi for phi_d < 0.
    Channel scales (1, 1.15, 1.66) / 1500 are applied on load; bins holding a negative value
    ("not measured") evaluate to 0 (``measured`` gives the mask).

    Reflection only and two-sided by flipping (as pbrt-v4's MeasuredBxDF): f = 0 unless wo and
    wi are on the same side. Sampling: bsdfkit's tabulated half-vector sampler (32 incidence
    angles x 90 theta_h rows x 64 azimuth columns, piecewise constant per solid angle, built from
    luminance(f) cos(theta_i) on load) mixed with 10 % cosine sampling; see bxdfs/merl.h.

    Spectral mode (``wavelengths=``): MERL data are RGB. Every bin is uplifted once (on the first
    spectral call) to pbrt-v4's ``RGBUnboundedSpectrum`` (2 max(rgb) times the Jakob & Hanika
    sigmoid of rgb / (2 max(rgb)); :func:`merl_uplift_coefficients`), kept as 4 float32 per bin
    (23.3 MB per table, beside the RGB table's 52.5 MB of float64 + float32 values). f(lambda) is the
    uplifted spectrum of the bin the RGB model reads (nearest) or the trilinear interpolation of
    the 8 bins' spectra at lambda with the RGB model's weights (linear); pdf and sampling are the
    RGB model's (wavelength-independent). In RGB mode the bins' RGB values are used as they are.

    Pickles by (path, digest): unpickling re-reads the file and refuses a changed one.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.binary`` file.
    interpolation : {"nearest", "linear"}, optional
        The lookup (above); default "nearest".
    digest : str, optional
        Expected SHA-256 of the file (hex).

    Raises
    ------
    ValueError
        A file that fails :func:`read_merl`'s checks, a digest that does not match, a bad
        ``interpolation``.
    OSError
        A file that cannot be read.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> path = bk.measured.write_merl("grey.binary", bk.Diffuse(0.5))
    >>> m = bk.MERL(path)
    >>> m.eval(bk.direction(0.5, 0.0), bk.direction(0.6, 2.0)).round(3)
    array([0.159, 0.159, 0.159])
    """

    # registry declarations (issue 10)
    aliases = ("merl",)
    examples = {"Cu α=0.2, linear": "merl metal=Cu alpha=0.2 interpolation=linear",
                "Cu α=0.2, nearest (MERL's lookup)": "merl metal=Cu alpha=0.2"}
    description = "MERL measured isotropic BRDF table (.binary), nearest or trilinear lookup"
    energy_conserving = False   # measured data: not guaranteed
    exact_eval = True
    reciprocal = True           # the lookup is symmetric in (wo, wi): MERL's phi_d fold
    two_sided = True
    transmission = False
    delta_only = False
    mitsuba = None              # Mitsuba 3 has no MERL plugin

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no MERL plugin (its ``measured`` plugin reads
        RGL tensor files: ``bsdfkit.Measured``)."""
        from ._mitsuba_export import no_plugin
        no_plugin(self, approximate, "Mitsuba 3 has no MERL plugin (its 'measured' plugin reads RGL "
                  "tensor files, bsdfkit.Measured)")
    knobs = (KnobDecl("interpolation", ("linear", "nearest"), "approximation",
                      "table lookup: trilinear between bin centres, or MERL's nearest bin"),)

    def cost_family(self) -> str:
        return _INTERPOLATION[self._params["interpolation"]]

    def describe(self) -> str:
        return f"MERL {os.path.basename(self._params['path'])} ({self._params['interpolation']})"

    __slots__ = ("_keep",)

    def __init__(self, path, interpolation="nearest", *, digest=None):
        """A MERL: the parameters are described in the class docstring (``help(bsdfkit.MERL)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        if not isinstance(interpolation, str) or interpolation not in _INTERPOLATION:
            raise ValueError(f"interpolation: must be 'nearest' or 'linear', got {interpolation!r}")
        if digest is not None and not isinstance(digest, str):
            raise TypeError(f"digest: expected a hex string or None, got {type(digest).__name__}")
        values, measured, ap, dig = read_merl(path)
        if digest is not None and digest != dig:
            raise ValueError(f"{ap}: digest: the file's content changed (expected {digest}, got {dig})")
        object.__setattr__(self, "_keep", (_merl_table(dig, interpolation == "linear", values), measured))
        super().__init__(path=ap, interpolation=interpolation, digest=dig)

    @classmethod
    def load(cls, path, interpolation="nearest") -> "MERL":
        """Load a MERL ``.binary`` file (same as ``MERL(path, interpolation)``)."""
        return cls(path, interpolation)

    @classmethod
    def from_metal(cls, name: str, alpha: float = 0.2, interpolation="nearest") -> "MERL":
        """A MERL table of ``Conductor.from_metal(name, alpha=alpha)`` (written once by
        :func:`bsdfkit.measured.write_merl` into :func:`example_dir`): an example file."""
        from .conductor import Conductor
        from ..measured import write_merl
        src = Conductor.from_metal(name, alpha=alpha)
        path = _example_file(f"merl_{name}_a{float(alpha):.6g}", ".binary", lambda p: write_merl(p, src))
        return cls(path, interpolation)

    @classmethod
    def _from_params(cls, p):
        return cls(p["path"], p["interpolation"], digest=p["digest"])

    def _make_core(self):
        return getattr(_core, _INTERPOLATION[self._params["interpolation"]])(table=self._keep[0])

    def _spectral_inputs(self) -> dict:
        # spectral/measured_spectral.h MERLNearestSpectral / MERLLinearSpectral: every bin uplifted once
        return {"coefficients": _merl_spectral_table(self._params["digest"], self._keep[0])}

    @property
    def values(self) -> np.ndarray:
        """The table, float64 (90 theta_h, 90 theta_d, 180 phi_d, 3 RGB), f in 1/sr (scales applied,
        not-measured bins 0). A copy."""
        return self._keep[0].values()

    @property
    def measured(self) -> np.ndarray:
        """bool (90, 90, 180, 3): False where the file holds a negative value (not measured)."""
        return self._keep[1]


# ================================================================ RGL tensor files

TENSOR_MAGIC = b"tensor_file\x00"
#: tensor_file dtype codes (Mitsuba Struct::Type / pbrt-v4 Tensor): code -> little-endian numpy dtype.
TENSOR_DTYPES = {1: "u1", 2: "i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<u8", 8: "<i8", 9: "<f2",
                 10: "<f4", 11: "<f8"}
_TENSOR_CODES = {np.dtype(v).newbyteorder("<") if np.dtype(v).itemsize > 1 else np.dtype(v): k
                 for k, v in TENSOR_DTYPES.items()}
_MAX_NDIM = 16


def parse_tensor(data: bytes, name: str = "<bytes>") -> dict:
    """Parse the bytes of a tensor file into ``{field: read-only numpy array}``.

    Layout (little-endian): ``b"tensor_file\\0"``, version (uint8 major = 1, uint8 minor = 0),
    uint32 field count; per field: uint16 name length, name (UTF-8), uint16 ndim, uint8 dtype
    code (1 u8, 2 i8, 3 u16, 4 i16, 5 u32, 6 i32, 7 u64, 8 i64, 9 f16, 10 f32, 11 f64), uint64
    absolute data offset, ndim x uint64 shape; the data C-contiguous at its offset. Every size
    is checked against the file's length before anything is read (a huge declared size is an
    error, never an allocation). ``name`` is used in the messages.
    """
    n = len(data)
    pos = 0

    def need(k, what):
        if pos + k > n:
            raise ValueError(f"{name}: {what}: truncated (needs {k} bytes at offset {pos}, the file has {n})")

    need(12, "header")
    if data[:12] != TENSOR_MAGIC:
        raise ValueError(f"{name}: header: not a tensor file (the first 12 bytes are {data[:12]!r}, "
                         f"expected {TENSOR_MAGIC!r})")
    pos = 12
    need(2, "version")
    major, minor = data[12], data[13]
    if (major, minor) != (1, 0):
        raise ValueError(f"{name}: version: unsupported tensor file version {major}.{minor} (expected 1.0)")
    pos = 14
    need(4, "n_fields")
    n_fields = int.from_bytes(data[14:18], "little")
    pos = 18
    if n_fields * 13 > n - pos:   # a field header has at least 13 bytes
        raise ValueError(f"{name}: n_fields: declares {n_fields} fields, more than the {n - pos} remaining bytes "
                         "can describe")
    fields = {}
    for k in range(n_fields):
        need(2, f"field #{k} name length")
        ln = int.from_bytes(data[pos:pos + 2], "little")
        pos += 2
        need(ln, f"field #{k} name")
        try:
            fname = data[pos:pos + ln].decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError(f"{name}: field #{k} name: not valid UTF-8") from None
        pos += ln
        need(2 + 1 + 8, f"field '{fname}' header")
        ndim = int.from_bytes(data[pos:pos + 2], "little")
        code = data[pos + 2]
        offset = int.from_bytes(data[pos + 3:pos + 11], "little")
        pos += 11
        if ndim > _MAX_NDIM:
            raise ValueError(f"{name}: field '{fname}': ndim: {ndim} dimensions (at most {_MAX_NDIM} supported)")
        need(8 * ndim, f"field '{fname}' shape")
        shape = tuple(int.from_bytes(data[pos + 8 * i:pos + 8 * i + 8], "little") for i in range(ndim))
        pos += 8 * ndim
        if code not in TENSOR_DTYPES:
            raise ValueError(f"{name}: field '{fname}': dtype: unknown dtype code {code}")
        if fname in fields:
            raise ValueError(f"{name}: field '{fname}': appears twice")
        dt = np.dtype(TENSOR_DTYPES[code])
        count = 1
        for s in shape:
            count *= s
        nbytes = count * dt.itemsize
        if offset > n or nbytes > n - offset:
            raise ValueError(f"{name}: field '{fname}': data: declares {nbytes} bytes at offset {offset}, "
                             f"the file has {n} bytes")
        arr = np.frombuffer(data, dt, count, offset).reshape(shape)
        fields[fname] = arr
    return fields


def read_tensor(path) -> dict:
    """Read a tensor file: ``{field name: read-only numpy array}`` (see :func:`parse_tensor`)."""
    ap, data, _ = _read_bytes(path, "tensor")
    return parse_tensor(data, ap)


def tensor_bytes(fields: dict, align: int = 8) -> bytes:
    """Serialize ``{name: array}`` as a tensor file (version 1.0, data blocks aligned to ``align``
    bytes, in the order given). Arrays are written little-endian and C-contiguous."""
    items = []
    for k, v in fields.items():
        a = np.asarray(v)
        dt = a.dtype.newbyteorder("<") if a.dtype.itemsize > 1 else a.dtype
        if dt not in _TENSOR_CODES:
            raise ValueError(f"fields: '{k}': dtype {a.dtype} has no tensor-file code")
        items.append((k.encode("utf-8"), np.ascontiguousarray(a, dtype=dt), _TENSOR_CODES[dt]))
    head = 12 + 2 + 4 + sum(2 + len(nm) + 2 + 1 + 8 + 8 * a.ndim for nm, a, _ in items)
    offsets, pos = [], head
    for _, a, _ in items:
        pos = (pos + align - 1) // align * align
        offsets.append(pos)
        pos += a.nbytes
    out = bytearray(pos)
    out[:12] = TENSOR_MAGIC
    out[12:14] = bytes([1, 0])
    out[14:18] = len(items).to_bytes(4, "little")
    p = 18
    for (nm, a, code), off in zip(items, offsets):
        out[p:p + 2] = len(nm).to_bytes(2, "little")
        p += 2
        out[p:p + len(nm)] = nm
        p += len(nm)
        out[p:p + 2] = a.ndim.to_bytes(2, "little")
        out[p + 2] = code
        out[p + 3:p + 11] = off.to_bytes(8, "little")
        p += 11
        for s in a.shape:
            out[p:p + 8] = int(s).to_bytes(8, "little")
            p += 8
        out[off:off + a.nbytes] = a.tobytes()
    return bytes(out)


def write_tensor(path, fields: dict, align: int = 8) -> str:
    """Write ``{name: array}`` as a tensor file (see :func:`tensor_bytes`); returns the absolute path."""
    ap = os.path.abspath(os.fspath(path))
    with open(ap, "wb") as fh:
        fh.write(tensor_bytes(fields, align))
    return ap


def _spectral_to_rgb_weights(wavelengths: np.ndarray) -> np.ndarray:
    """(3, n_lambda) weights W with rgb = W @ samples: the linear sRGB (D65 white) of the
    reflectance spectrum that interpolates the samples linearly in wavelength (constant beyond
    the end samples, as the tables are interpolated), lit by CIE D65 and observed by the CIE 1931
    2-degree observer, normalised so that a reflectance of 1 gives (1, 1, 1). Exact on the
    tables (the projection is linear, the interpolations are linear)."""
    import colour
    lam = np.arange(360.0, 831.0)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(
        colour.SpectralShape(360, 830, 1)).values          # (471, 3)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(360, 830, 1)).values
    hats = np.stack([np.interp(lam, wavelengths, np.eye(len(wavelengths))[j]) for j in range(len(wavelengths))],
                    axis=1)                                  # (471, n_lambda)
    xyz_w = (cmfs * d65[:, None]).T @ hats / float(np.sum(cmfs[:, 1] * d65))
    m = np.asarray(colour.models.RGB_COLOURSPACE_sRGB.matrix_XYZ_to_RGB)
    w = m @ xyz_w
    return w / w.sum(axis=1, keepdims=True)   # white (reflectance 1) -> exactly (1, 1, 1)


def _check_field(fields, fname, name, ndim, dtype):
    if fname not in fields:
        raise ValueError(f"{name}: field '{fname}': missing")
    a = fields[fname]
    if a.ndim != ndim:
        raise ValueError(f"{name}: field '{fname}': expected {ndim} dimensions, got shape {a.shape}")
    if a.dtype != np.dtype(dtype):
        raise ValueError(f"{name}: field '{fname}': expected dtype {np.dtype(dtype).name}, got {a.dtype.name}")
    return a


def _finite(a, fname, name, nonneg=False):
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: field '{fname}': contains NaN or infinite values")
    if nonneg and a.size and float(a.min()) < 0:
        raise ValueError(f"{name}: field '{fname}': contains negative values")


def validate_measured(fields: dict, name: str) -> dict:
    """Check the fields of an RGL measured-BRDF tensor file as pbrt-v4 / Mitsuba do (names,
    dtypes, shapes, consistency), plus values (finite; a spectral file's RGB projection within
    float32's range, and the largest value the evaluation can reach, max |rgb| [max ndf /
    (4 min sigma)] / kMinCos, too; ndf, sigma, vndf, luminance >= 0; theta_i increasing in [0, pi/2]; phi_i
    increasing; the anisotropic reduction 1, 2 or 4). Returns the derived description
    (isotropic, reduction, jacobian, rgb table, ...)."""
    desc = _check_field(fields, "description", name, 1, np.uint8)
    theta = _check_field(fields, "theta_i", name, 1, np.float32)
    phi = _check_field(fields, "phi_i", name, 1, np.float32)
    ndf = _check_field(fields, "ndf", name, 2, np.float32)
    sigma = _check_field(fields, "sigma", name, 2, np.float32)
    vndf = _check_field(fields, "vndf", name, 4, np.float32)
    lum = _check_field(fields, "luminance", name, 4, np.float32)
    jac = _check_field(fields, "jacobian", name, 1, np.uint8)
    spectral = "wavelengths" in fields
    if spectral:
        wl = _check_field(fields, "wavelengths", name, 1, np.float32)
        spec = _check_field(fields, "spectra", name, 5, np.float32)
    else:
        spec = _check_field(fields, "rgb", name, 5, np.float32)
    nphi, nth = phi.shape[0], theta.shape[0]
    if nphi < 1 or nth < 1:
        raise ValueError(f"{name}: field 'phi_i' / 'theta_i': must not be empty")
    if jac.shape != (1,):
        raise ValueError(f"{name}: field 'jacobian': expected shape (1,), got {jac.shape}")
    for fname, a in (("vndf", vndf), ("luminance", lum), ("spectra" if spectral else "rgb", spec)):
        if a.shape[:2] != (nphi, nth):
            raise ValueError(f"{name}: field '{fname}': leading shape {a.shape[:2]} does not match "
                             f"(len(phi_i), len(theta_i)) = {(nphi, nth)}")
    if lum.shape[2] != lum.shape[3]:
        raise ValueError(f"{name}: field 'luminance': slices must be square, got {lum.shape[2:]}")
    if spec.shape[3:] != lum.shape[2:]:
        raise ValueError(f"{name}: field '{'spectra' if spectral else 'rgb'}': slices {spec.shape[3:]} do not match "
                         f"'luminance' {lum.shape[2:]}")
    nch = wl.shape[0] if spectral else 3
    if spec.shape[2] != nch:
        raise ValueError(f"{name}: field '{'spectra' if spectral else 'rgb'}': axis 2 has {spec.shape[2]} entries, "
                         f"expected {nch}")
    for fname, a in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("luminance", lum)):
        if min(a.shape[-2:]) < 2:
            raise ValueError(f"{name}: field '{fname}': 2-D slices must be at least 2 x 2, got {a.shape[-2:]}")
        _finite(a, fname, name, nonneg=True)
    _finite(spec, "spectra" if spectral else "rgb", name)
    _finite(theta, "theta_i", name)
    _finite(phi, "phi_i", name)
    if np.any(np.diff(theta) <= 0) or theta[0] < 0 or theta[-1] > np.pi / 2 + 1e-5:
        raise ValueError(f"{name}: field 'theta_i': must increase strictly within [0, pi/2]")
    if np.any(np.diff(phi) <= 0):
        raise ValueError(f"{name}: field 'phi_i': must increase strictly")
    isotropic = nphi <= 2
    reduction = 1
    if not isotropic:
        span = float(phi[-1]) - float(phi[0])    # in float64: float32's difference can overflow
        reduction = int(np.rint(2 * np.pi / span))
        if reduction not in (1, 2, 4):
            raise ValueError(f"{name}: field 'phi_i': spans {span:.4g} rad: reduction "
                             f"{reduction} (2 pi / span) must be 1, 2 or 4")
    if spectral:
        _finite(wl, "wavelengths", name)
        if np.any(np.diff(wl) <= 0):
            raise ValueError(f"{name}: field 'wavelengths': must increase strictly")
        w = _spectral_to_rgb_weights(wl.astype(np.float64))
        rgb = np.einsum("cl,ptlyx->ptcyx", w, spec.astype(np.float64))
    else:
        rgb = spec.astype(np.float64)
    rgb_max = float(np.abs(rgb).max()) if rgb.size else 0.0
    if spectral and rgb_max > _F32_MAX:
        raise ValueError(f"{name}: field 'spectra': its RGB projection reaches {rgb_max:.9g}, beyond "
                         f"float32's max {_F32_MAX:.9g} (the RGB table is evaluated in float32 too)")
    # The largest value the evaluation can reach: f = rgb [ndf / (4 sigma) with the jacobian] /
    # max(cos_i, kMinCos) (bxdfs/measured.h), every factor a convex combination of table entries.
    # Beyond float32's max a float32 call's arithmetic overflows and the kernels' output check
    # would turn that into 0: such a file is refused here instead.
    jacobian = bool(jac[0])
    spec_name = "spectra" if spectral else "rgb"
    bound = rgb_max
    named = f"field '{spec_name}'"
    if jacobian and bound > 0:
        s_pos = sigma[sigma > 0]
        if s_pos.size == 0:
            raise ValueError(f"{name}: field 'sigma': all zero, and the jacobian divides by it")
        bound *= float(ndf.max()) / (4.0 * float(s_pos.min()))
        named = f"fields '{spec_name}', 'ndf', 'sigma'"
    bound /= _MEASURED_MIN_COS
    if bound > _F32_MAX:
        raise ValueError(f"{name}: {named}: the evaluation can reach {bound:.9g} (max |rgb|"
                         + (" * max ndf / (4 min sigma)" if jacobian else "")
                         + f" / {_MEASURED_MIN_COS:g}), beyond float32's max {_F32_MAX:.9g} (the model is "
                         "evaluated in float32 too)")
    return dict(description=bytes(desc).decode("utf-8", "replace"), isotropic=isotropic, reduction=reduction,
                jacobian=jacobian, spectral=spectral, rgb=rgb, theta_i=theta.astype(np.float64),
                phi_i=phi.astype(np.float64))


_MEASURED: "collections.OrderedDict" = collections.OrderedDict()   # digest -> (fields, info, _core table)
_IN_MEMORY: "weakref.WeakValueDictionary" = weakref.WeakValueDictionary()   # digest -> a live in-memory Measured


def _measured_entry(digest, data: bytes | None, name: str):
    with _LOCK:
        e = _MEASURED.get(digest)
        if e is not None:
            _MEASURED.move_to_end(digest)
            return e
    if data is None:
        return None
    fields = parse_tensor(data, name)
    info = validate_measured(fields, name)
    f64 = {k: np.asarray(fields[k], np.float64) for k in ("ndf", "sigma", "vndf", "luminance")}
    try:
        table = _core.MeasuredTable(f64["ndf"], f64["sigma"], f64["vndf"], f64["luminance"], info["rgb"],
                                    info["phi_i"].tolist(), info["theta_i"].tolist(), info["isotropic"],
                                    info["jacobian"], info["reduction"])
    except ValueError as e:
        raise ValueError(f"{name}: field {e}") from None
    e = (fields, info, table, data)
    with _LOCK:
        _MEASURED[digest] = e
        while len(_MEASURED) > _MAX_TABLES:
            _MEASURED.popitem(last=False)
    return e


_SPECTRA: "collections.OrderedDict" = collections.OrderedDict()   # digest -> _core.MeasuredSpectraTable


def _measured_spectra(digest: str, fields: dict, info: dict):
    """The spectra warp of a spectral tensor file (built on the first spectral call, shared)."""
    with _LOCK:
        t = _SPECTRA.get(digest)
        if t is not None:
            _SPECTRA.move_to_end(digest)
            return t
    t = _core.MeasuredSpectraTable(np.asarray(fields["spectra"], np.float64),
                                   np.asarray(fields["wavelengths"], np.float64).tolist(),
                                   info["phi_i"].tolist(), info["theta_i"].tolist())
    with _LOCK:
        _SPECTRA[digest] = t
        while len(_SPECTRA) > _MAX_TABLES:
            _SPECTRA.popitem(last=False)
    return t


class Measured(BxDF):
    """A measured BRDF in the RGL tensor format (Dupuy & Jakob 2018; the ``.bsdf`` files of the
    RGL material database), as pbrt-v4's ``MeasuredBxDF`` and Mitsuba 3's ``measured`` read it.

    path: the tensor file (``*_rgb.bsdf`` or ``*_spec.bsdf``). Every field is validated (see
    :func:`validate_measured`). Spectral files are projected to linear sRGB on load (D65, CIE
    1931 2-degree observer; exact on the tables, see ``_spectral_to_rgb_weights``); the spectral
    tables stay available as ``fields["spectra"]`` / ``fields["wavelengths"]``.

    Evaluation, pdf and sampling go through the luminance and VNDF warps (bilinear warps with an
    exact inverse: bsdfkit/core/warp2d.h), as Mitsuba; the ``jacobian`` flag is honoured as
    Mitsuba does (pbrt-v4 always multiplies by ndf / (4 sigma)); anisotropic files with a
    2- or 4-fold reduction are folded as Mitsuba does (pbrt-v4 rejects them). Reflection only,
    two-sided by flipping (as pbrt-v4; Mitsuba's plugin is one-sided). Negative (out-of-gamut)
    RGB values evaluate to 0.

    Tables are shared and immutable. A model loaded from a file pickles by (path, SHA-256 digest)
    and refuses a changed file when unpickled; a model built in memory (:func:`bsdfkit.measured.tabulate`)
    pickles by value (its serialized tensor file).

    Spectral mode (``wavelengths=``, spectral files only; an RGB file raises NotImplementedError,
    as pbrt-v4 and Mitsuba's spectral variants need spectral files): f at each wavelength comes
    from the file's ``spectra`` tensor at the same sample-space point the RGB mode reads, linear in
    wavelength between the file's tabulated wavelengths (the multilinear interpolation of pbrt-v4's
    MeasuredBxDF and Mitsuba's ``measured``), negative values clamped to 0 as pbrt-v4 does,
    times ndf / (4 sigma); wavelengths outside the file's range take its end values (both
    renderers clamp the interpolation weight). pdf and sampling are the RGB mode's (the luminance
    and VNDF warps do not depend on the wavelength). In RGB mode the spectra are projected once,
    at load (above).

    Parameters
    ----------
    path : str or os.PathLike, optional
        The tensor file; or
    data : bytes, optional
        The tensor file's bytes (exactly one of ``path`` and ``data``).
    digest : str, optional
        Expected SHA-256 of the file (hex).

    Raises
    ------
    ValueError
        Both or neither of ``path`` and ``data``; a field that fails validation (named); a
        digest that does not match.
    TypeError
        ``data`` that is not bytes.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.measured.tabulate(bk.Diffuse(0.5), resolution=8)
    >>> isinstance(m, bk.Measured), m.eval(bk.direction(0.5, 0.0), bk.direction(0.6, 2.0)).shape
    (True, (3,))
    """

    # registry declarations (issue 10)
    aliases = ("measured", "rgl")
    examples = {"tabulated Au, αx=0.15, αy=0.4": "measured metal=Au alpha=0.15 alpha_y=0.4"}
    description = "RGL measured BRDF tensor file (.bsdf, Dupuy & Jakob 2018), as pbrt-v4 and Mitsuba read it"
    energy_conserving = False   # measured data: not guaranteed
    exact_eval = True
    reciprocal = False          # the warps are conditioned on wo: f(wo, wi) != f(wi, wo) between grid points
    two_sided = True
    transmission = False
    delta_only = False
    mitsuba = "measured"
    knobs = ()                  # the tabulation resolution is a knob of bk.measured.tabulate

    def cost_family(self) -> str:
        return "Measured"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Mitsuba 3's ``measured`` plugin on the same file (Mitsuba's plugin is one-sided: it
        agrees with this model for wo.z > 0). A model built from bytes (``data=``, e.g.
        ``bsdfkit.measured.tabulate``) has no file: ValueError (``save()`` it first)."""
        from ._mitsuba_export import check_approximate
        check_approximate(approximate)
        if self._params["path"] is None:
            raise ValueError("to_mitsuba: a Measured model built from bytes has no file for Mitsuba's "
                             "measured plugin; save() it first")
        return {"type": "measured", "filename": self._params["path"]}

    def describe(self) -> str:
        p = self._params
        return f"Measured {os.path.basename(p['path'])}" if p["path"] else "Measured (tabulated)"

    __slots__ = ("_keep", "__weakref__")

    def __init__(self, path=None, *, digest=None, data=None):
        """A Measured: the parameters are described in the class docstring (``help(bsdfkit.Measured)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        if (path is None) == (data is None):
            raise ValueError("path, data: give exactly one of them")
        if data is not None:
            if not isinstance(data, (bytes, bytearray, memoryview)):
                raise TypeError(f"data: expected bytes, got {type(data).__name__}")
            data, ap, name = bytes(data), None, "<tensor data>"
        else:
            ap, data, _ = _read_bytes(path, "tensor")
            name = ap
        dig = hashlib.sha256(data).hexdigest()
        if digest is not None and digest != dig:
            raise ValueError(f"{name}: digest: the content changed (expected {digest}, got {dig})")
        object.__setattr__(self, "_keep", _measured_entry(dig, data, name))   # (fields, info, table, bytes)
        super().__init__(path=ap, digest=dig)
        if ap is None:   # rebuilt from its parameters (path None, digest) while alive: _from_params
            _IN_MEMORY[dig] = self

    @classmethod
    def load(cls, path) -> "Measured":
        """Load an RGL tensor file (same as ``Measured(path)``)."""
        return cls(path)

    @classmethod
    def from_metal(cls, name: str, alpha: float = 0.2, alpha_y: float | None = None, resolution: int = 32) -> "Measured":
        """The tabulation (:func:`bsdfkit.measured.tabulate`) of ``Conductor.from_metal(name, alpha,
        alpha_y)`` saved once into :func:`example_dir` and loaded from there: an example file."""
        from .conductor import Conductor
        from ..measured import tabulate
        ay = alpha if alpha_y is None else alpha_y
        src = Conductor.from_metal(name, alpha_x=alpha, alpha_y=ay)
        stem = f"tensor_{name}_a{float(alpha):.6g}_{float(ay):.6g}_r{int(resolution)}_rgb"
        path = _example_file(stem, ".bsdf", lambda p: tabulate(src, resolution=resolution).save(p))
        return cls(path)

    @classmethod
    def from_bytes(cls, data: bytes) -> "Measured":
        """A model from the bytes of a tensor file (kept in memory; pickles by value)."""
        return cls(data=data)

    @classmethod
    def _from_params(cls, p):
        if p["path"] is not None:
            return cls(p["path"], digest=p["digest"])
        # an in-memory model (from_bytes, tabulate): its parameters are (None, digest); the bytes
        # are those of a live model with that digest, else of the table cache
        live = _IN_MEMORY.get(p["digest"])
        if live is not None:
            return live
        entry = _measured_entry(p["digest"], None, "")
        if entry is None:
            raise ValueError(f"digest: no in-memory Measured model with sha256 {p['digest'][:12]}... is alive any "
                             "more, and its bytes are not cached; keep the model, or save() it and load the file")
        return cls(data=entry[3])

    def __reduce__(self):
        if self._params["path"] is None:
            return (Measured.from_bytes, (self._entry()[3],))
        return super().__reduce__()

    def __repr__(self):
        p = self._params
        if p["path"] is None:
            return f"Measured.from_bytes(<{len(self._entry()[3])} bytes, sha256 {p['digest'][:12]}...>)"
        return f"Measured({p['path']!r}, digest={p['digest']!r})"

    def _entry(self):
        return self._keep

    def _make_core(self):
        return _core.Measured(table=self._entry()[2])

    def _spectral_inputs(self) -> dict:
        # spectral/measured_spectral.h MeasuredSpectral: the file's spectra per wavelength
        fields, info, _, _ = self._entry()
        return {"spectra": _measured_spectra(self._params["digest"], fields, info)}

    def _has_spectral_kernel(self) -> bool:
        return bool(self._entry()[1]["spectral"])  # a file with spectra

    def _no_spectral_reason(self) -> str:
        return ("wavelengths: this tensor file holds RGB data (an `rgb` field, e.g. *_rgb.bsdf or "
                "bsdfkit.measured.tabulate); spectral mode needs a spectral file (`spectra` and `wavelengths` "
                "fields, *_spec.bsdf), as pbrt-v4 and Mitsuba's spectral variants do; call without wavelengths=")

    @property
    def fields(self) -> dict:
        """The file's fields, ``{name: read-only numpy array}``."""
        return dict(self._entry()[0])

    @property
    def file_description(self) -> str:
        """The file's ``description`` field (text)."""
        return self._entry()[1]["description"]

    @property
    def isotropic(self) -> bool:
        return self._entry()[1]["isotropic"]

    @property
    def reduction(self) -> int:
        return self._entry()[1]["reduction"]

    @property
    def jacobian(self) -> bool:
        return self._entry()[1]["jacobian"]

    @property
    def spectral(self) -> bool:
        return self._entry()[1]["spectral"]

    def save(self, path) -> str:
        """Write the tensor file (byte-identical to what was loaded); returns the absolute path."""
        ap = os.path.abspath(os.fspath(path))
        with open(ap, "wb") as fh:
            fh.write(self._entry()[3])
        return ap
