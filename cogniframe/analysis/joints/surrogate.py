"""The joint surrogate (``method="surrogate"``): each joint family's solid-FE super-element as a
fitted function of the joint's own geometry, microseconds per joint, trained offline by
`tools/train_joint_surrogate.py` on the solid FE and shipped as `cogniframe/data/joint_surrogate.json`.

What is fitted (docs/stiffness-model.md, "The joint surrogate"):

1. The super-element K (6n x 6n, at TPU factor 1) has the joint's six rigid-body modes as its null
   space. With the last body held (the support body, else the last socket's rod), the stiffness of
   the others is the leading block A (6(n-1) square, positive definite), and K = B^T A B exactly,
   B the motion of each body relative to the held one carried rigidly to its reference point. So
   A holds everything and any positive definite A gives a K with exactly the right null space.
2. A is made dimensionless and smooth: each rod body in its own socket frame (x along the rod),
   rotations scaled by `LENGTH_MM`, divided by the TPU modulus E (every stiffness in the FE is
   proportional to it at a fixed Poisson's ratio).
3. Its matrix logarithm L = logm(A) is fitted entry by entry (its upper triangle) as a quadratic
   ridge regression in the joint's features (log sizes, socket directions and offsets, whitened
   by principal components): the log-Euclidean mean of positive definite matrices, so every
   prediction exp(L) is positive definite, and power laws in the sizes (k ~ wall^3, depth^2, ...)
   are linear in it.

The features are read from the part itself (`features`): what is constant over the training set
must match (the Poisson's ratio, the screw hole, ...), what varies must lie in its training range;
otherwise `predict` returns None with the reason, and the caller falls back to the FE.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from .model import JointStiffness, _block_rot, interface, joint_kind, tpu_moduli

LENGTH_MM = 10.0  # rotations scaled by this length: translational and rotational entries alike in N/mm
DATA_FILE = Path(__file__).resolve().parents[2] / "data" / "joint_surrogate.json"
# sha256 of the data file this code was fitted with (written by the training tool): a different
# file is refused, and retraining edits this line, so every cache key over the source changes too
DATA_SHA256 = "bfd15b9e4cd69b9a7c345ea9355a081bb3718dd9064e17290e29c053b19fc387"
_ABS_TOL = 1e-6  # a feature constant over the training set must equal it to this (mm, rad, ratios)
_BOX_SLACK = 0.02  # a varying feature may exceed its sampled range by this share of it: the design box ends (a hypercube never samples them exactly)


@dataclass(frozen=True)
class Family:
    """One joint family's fit (see the module docstring)."""

    kind: str
    labels: tuple[str, ...]  # the training parts' body labels (socket rods, then "body")
    names: tuple[str, ...]  # every feature
    fixed: tuple[float | None, ...]  # the value of a feature constant over the training set, else None
    lo: tuple[float, ...]  # training range of each feature
    hi: tuple[float, ...]
    mean: tuple[float, ...]  # standardisation of the varying features
    std: tuple[float, ...]
    rot: tuple[tuple[float, ...], ...]  # principal directions of the standardised varying features (k x p)
    scale: tuple[float, ...]  # their standard deviations (whitening)
    quadratic: int  # products of the first this many components (0: linear)
    ridge: float
    coef: tuple[tuple[float, ...], ...]  # (terms x outputs): log-matrix entries of A
    n_train: int

    @cached_property
    def _arrays(self) -> tuple:
        """The numbers as arrays, made once per process (the tuples keep the dataclass hashable)."""
        return (np.array([f is None for f in self.fixed]), np.asarray(self.mean), np.asarray(self.std),
                np.asarray(self.rot).T / np.asarray(self.scale), np.asarray(self.coef))

    def basis(self, x: np.ndarray) -> np.ndarray:
        """Regression terms of feature rows x (N x len(names))."""
        v, mean, std, proj, _ = self._arrays
        return _terms((x[:, v] - mean) / std @ proj, self.quadratic)

    def log_entries(self, x: np.ndarray) -> np.ndarray:
        """The fitted upper triangle of logm(A) at feature rows x."""
        return self.basis(x) @ self._arrays[4]

    def to_json(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}

    @staticmethod
    def from_json(d: dict) -> "Family":
        def tup(v):
            return tuple(tup(x) for x in v) if isinstance(v, list) else v

        return Family(**{k: tup(v) for k, v in d.items()})


def _terms(p: np.ndarray, quadratic: int) -> np.ndarray:
    """1, every component, and the products of the first `quadratic` components (squares included)."""
    cols = [np.ones(len(p)), *p.T]
    k = min(int(quadratic), p.shape[1])
    cols += [p[:, i] * p[:, j] for i in range(k) for j in range(i, k)]
    return np.column_stack(cols)


# -- features and the matrix representation --------------------------------------------------------

def features(spec, part) -> tuple[tuple[str, ...], np.ndarray]:
    """(names, values) of everything the joint's FE reads, in a fixed order: rod diameter, interface
    layer, wall, Poisson's ratio, per socket its seat, depth, bore clearance, direction and port,
    and the part's numeric params (hinge thickness for knees, the core link's bolt hole and tab)."""
    itf = interface(spec, 1.0)
    e, g = tpu_moduli(spec, 1.0)
    d = float(spec.rods.diameter)
    kind = joint_kind(part)
    names = ["log_rod_d", "log_interface_h", "nu"]
    vals = [math.log(d), math.log(itf.h), e / (2 * g) - 1]
    if kind.surrogate_reads_wall:  # the pegged link's columns have the connector's own wall, not joints.wall
        names.insert(2, "log_wall")
        vals.insert(2, math.log(part.wall))
    for i, s in enumerate(part.sockets):
        names += [f"s{i}_log_seat", f"s{i}_log_depth", f"s{i}_clearance", *(f"s{i}_dir_{a}" for a in "xyz"),
                  *(f"s{i}_port_{a}" for a in "xyz")]
        vals += [math.log(max(s.seat, 1e-3)), math.log(s.depth), s.bore - d, *map(float, s.direction), *map(float, s.port)]
    n, v = kind.surrogate_features(part)  # the shape of its own (the pegged link's arch and columns)
    names += n
    vals += v
    for k, v in part.params:
        if k in ("kind", "mirror") or not kind.surrogate_reads(k):
            continue
        if isinstance(v, bool):
            names.append(f"p_{k}")
            vals.append(float(v))
        elif isinstance(v, (int, float)):
            names.append(f"p_{k}" if k != "hinge_thickness" else "log_hinge")
            vals.append(math.log(v) if k == "hinge_thickness" else float(v))
        elif isinstance(v, (tuple, list)) and all(isinstance(x, (int, float)) for x in v):
            names += [f"p_{k}_{j}" for j in range(len(v))]
            vals += [float(x) for x in v]
        else:  # a name (the screw): only the same one is in the box
            names.append(f"p_{k}={v}")
            vals.append(1.0)
    return tuple(names), np.array(vals, float)


def socket_frame(direction) -> np.ndarray:
    """Rows: the socket's x (out along the rod), y = z_part x x (horizontal), z = x x y."""
    a, b, c = (float(v) for v in direction)
    r = math.sqrt(a * a + b * b + c * c)
    a, b, c = a / r, b / r, c / r
    n = math.hypot(a, b)  # z_part x x = (-b, a, 0), of length n
    p, q = (-b / n, a / n) if n > 1e-9 else (0.0, 1.0)
    return np.array([[a, b, c], [p, q, 0.0], [-c * q, c * p, a * q - b * p]])  # rows x, y, x cross y


def _frames(part, labels) -> np.ndarray:
    """6n x 6n: part frame -> the bodies' frames (rods: socket frames; the support: the part's)."""
    blocks = []
    for i, lab in enumerate(labels):
        r = socket_frame(part.sockets[i].direction) if lab != "body" else np.eye(3)
        blocks.append(_block_rot(r))
    n = len(blocks)
    T = np.zeros((6 * n, 6 * n))
    for i, b in enumerate(blocks):
        T[6 * i:6 * i + 6, 6 * i:6 * i + 6] = b
    return T


def _transfer(refs, frames: np.ndarray) -> np.ndarray:
    """B (6(n-1) x 6n, in the bodies' frames): each body's motion less the held (last) body's carried rigidly to it."""
    from ..framefe import rigid_transfer

    n = len(refs)
    B = np.zeros((6 * (n - 1), 6 * n))
    last = np.asarray(refs[-1], float)
    for i in range(n - 1):
        B[6 * i:6 * i + 6, 6 * i:6 * i + 6] = np.eye(6)
        Ti = rigid_transfer(last, np.asarray(refs[i], float))  # part frame: u_i = Ti u_last
        Ri = frames[6 * i:6 * i + 6, 6 * i:6 * i + 6]
        Rl = frames[6 * (n - 1):, 6 * (n - 1):]
        B[6 * i:6 * i + 6, 6 * (n - 1):] = -Ri @ Ti @ Rl.T
    return B


def _scaling(n: int) -> np.ndarray:
    return np.tile([1.0, 1.0, 1.0, LENGTH_MM, LENGTH_MM, LENGTH_MM], n)


def log_target(unit: JointStiffness, part, e_mpa: float) -> np.ndarray:
    """The fitted quantity of an FE super-element (at factor 1): the upper triangle of logm of the
    dimensionless held-last block A (module docstring)."""
    T = _frames(part, unit.labels)
    K = T @ unit.matrix @ T.T  # the bodies' frames
    s = _scaling(len(unit.labels))
    K = K / np.outer(s, s) / e_mpa
    m = K.shape[0] - 6
    A = 0.5 * (K[:m, :m] + K[:m, :m].T)
    w, V = np.linalg.eigh(A)
    if w.min() <= 0:
        raise ValueError(f"{unit.name}: the held-last block is not positive definite (min eigenvalue {w.min():.3g})")
    L = (V * np.log(w)) @ V.T
    return L[np.triu_indices(m)]


def _refs(part, labels) -> list:
    refs = [tuple(map(float, s.mouth())) for s in part.sockets]
    if len(labels) > len(part.sockets):
        refs.append((0.0, 0.0, 0.0))
    return refs


def matrix_from_log(y: np.ndarray, part, labels, e_mpa: float) -> np.ndarray:
    """The super-element (part frame, factor 1) from a predicted log-triangle `y` (inverse of `log_target`)."""
    n = len(labels)
    m = 6 * (n - 1)
    L = np.zeros((m, m))
    L[np.triu_indices(m)] = y
    L = L + np.triu(L, 1).T
    w, V = np.linalg.eigh(L)
    s = _scaling(n - 1)
    A = (V * np.exp(w)) @ V.T * np.outer(s, s) * e_mpa
    T = _frames(part, labels)
    B = _transfer(_refs(part, labels), T)
    K = T.T @ (B.T @ A @ B) @ T
    return 0.5 * (K + K.T)


# -- the shipped fit ------------------------------------------------------------------------------

@lru_cache(maxsize=4)
def _load(path: str) -> dict:
    """The fit file (read once per process: it is package data, fixed for a given install)."""
    raw = Path(path).read_bytes()
    import hashlib

    if path == str(DATA_FILE) and hashlib.sha256(raw).hexdigest() != DATA_SHA256:
        raise RuntimeError(f"{path} is not the joint surrogate this code was trained with (sha256 differs); "
                           "reinstall cogniframe or rerun tools/train_joint_surrogate.py")
    doc = json.loads(raw)
    return {"meta": doc["meta"], "families": {k: Family.from_json(v) for k, v in doc["families"].items()}}


def families(path: Path | None = None) -> dict[str, Family]:
    return _load(str(path or DATA_FILE))["families"]


def out_of_box(fam: Family, names, x: np.ndarray) -> str | None:
    """Why features `x` are outside the family's training box, or None when inside."""
    if tuple(names) != fam.names:
        return "its features differ from the training parts' (another socket layout or part params)"
    for nm, v, f, lo, hi in zip(names, x, fam.fixed, fam.lo, fam.hi):
        if f is not None:
            if abs(v - f) > _ABS_TOL * max(1.0, abs(f)):
                return f"{nm} = {v:.4g}, trained only at {f:.4g}"
        else:
            slack = _BOX_SLACK * (hi - lo)
            if v < lo - slack or v > hi + slack:
                return f"{nm} = {v:.4g} outside its training range {lo:.4g} to {hi:.4g}"
    return None


def box_tests(spec, parts) -> dict[str, tuple[str | None, np.ndarray | None]]:
    """{joint part name: (why it is outside its family's training box or None, its features when
    they were read)} for the originals among `parts` (not the mirrors): what `outside_reasons` and
    `predict` read, so that one check reads each joint's features once."""
    from .mirror import is_mirror

    fams = families()
    return {p.name: _box_test(fams, spec, p) for p in parts if not is_mirror(p)}


def outside_reasons(spec, parts, tests: dict | None = None) -> dict[str, str]:
    """{joint part name: why} for the joints the surrogate does not cover (a mirror follows its
    original, like `joints.surrogate_models`). ``tests``: `box_tests` of these parts when the
    caller has them."""
    from .mirror import is_mirror, mirror_original

    tests = box_tests(spec, parts) if tests is None else tests
    out = {}
    for p in parts:
        if is_mirror(p):
            continue
        why = tests[p.name][0]
        if why is not None:
            out[p.name] = why
    for p in parts:
        if not is_mirror(p):
            continue
        try:
            found = mirror_original(p, parts)
        except ValueError as exc:
            out[p.name] = f"not an exact mirror image ({exc})"
            continue
        if found is None:
            out[p.name] = "its original is not in the part list"
        elif found[0].name in out:
            out[p.name] = f"its original {found[0].name} is outside"
    return out


def family_of(part) -> str:
    """The fit a joint belongs to: its kind, and for a core link its joint to the core (the pegged
    connector and the bolted tab are different shapes with different features)."""
    return joint_kind(part).surrogate_family


def _box_test(fams: dict, spec, part) -> tuple[str | None, np.ndarray | None]:
    """(why the joint is outside its family's box or None, its features when they were read)."""
    from .mirror import is_mirror

    if is_mirror(part):  # fitted on originals: a mirror is its original's prediction, reflected
        return "a mirrored joint (reflected from its original's prediction, not predicted itself)", None
    fam = fams.get(family_of(part))
    if fam is None:
        return f"no surrogate for {family_of(part)} joints", None
    n = len(part.sockets) + (1 if len(fam.labels) > len(part.sockets) else 0)
    if n != len(fam.labels):
        return f"{n} bodies, trained on {len(fam.labels)}", None
    names, x = features(spec, part)
    return out_of_box(fam, names, x), x


def predict(spec, part, factor: float | None = None, path: Path | None = None,
            tested: tuple | None = None) -> tuple[JointStiffness | None, str | None]:
    """(super-element, None) from the fit, scaled by the TPU factor like the FE; or (None, why) when
    the joint is outside the training box (or its family was not trained): the caller runs the FE.
    ``tested``: the part's `box_tests` entry (the shipped fit's) when the caller has it."""
    import time

    from .model import TPU_PRINTED_MODULUS_FACTOR

    t0 = time.perf_counter()
    fams = families(path)
    why, x = _box_test(fams, spec, part) if tested is None else tested
    if why is not None:
        return None, why
    fam = fams[family_of(part)]
    labels = tuple(s.rod for s in part.sockets) + (("body",) if len(fam.labels) > len(part.sockets) else ())
    y = fam.log_entries(x[None, :])
    e_unit = tpu_moduli(spec, 1.0)[0]
    K = matrix_from_log(y[0], part, labels, e_unit)
    f = TPU_PRINTED_MODULUS_FACTOR if factor is None else float(factor)
    refs = tuple(tuple(r) for r in _refs(part, labels))
    return JointStiffness(part.name, "surrogate", labels, refs, tuple(map(tuple, (f * K).tolist())), 0,
                          time.perf_counter() - t0), None


# -- the fit (used by tools/train_joint_surrogate.py only) -----------------------------------------

def fit_family(kind: str, labels, names, X: np.ndarray, Y: np.ndarray, quadratic=(0, 4, 6, 8, 10, 12, 16),
               rel_sv: float = 1e-2, ridges=(1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1)) -> tuple[Family, dict]:
    """Fit one family: features X (N x p), log-triangles Y (N x m). Constant features are fixed;
    the varying ones standardised and whitened (principal components with singular values above
    `rel_sv` of the largest: the rest is rounding); the number of leading components with
    quadratic terms (`quadratic`: an int or the candidates) and the ridge weight are picked by the
    leave-one-out error of Y (closed form from the hat matrix), the quadratic terms only where
    they have at least two samples each. Returns the family and {(quadratic, ridge): LOO RMS}.
    Raises ValueError when there are too few samples for even the linear terms."""
    X = np.asarray(X, float)
    rng = X.max(0) - X.min(0)
    fixed_mask = rng <= _ABS_TOL * np.maximum(1.0, np.abs(X).max(0))
    Xv = X[:, ~fixed_mask]
    mean, std = Xv.mean(0), Xv.std(0)
    Z = (Xv - mean) / std
    _, sv, vt = np.linalg.svd(Z, full_matrices=False)
    k = int((sv > rel_sv * sv[0]).sum())
    rot, scale = vt[:k], sv[:k] / math.sqrt(len(X))
    # a deterministic sign for each principal direction (SVD's is arbitrary)
    sign = np.sign(rot[np.arange(k), np.abs(rot).argmax(1)])
    rot = rot * sign[:, None]
    P = Z @ rot.T / scale
    loo = {}
    best = None
    for q in sorted({min(int(x), k) for x in np.atleast_1d(quadratic)}):
        Phi = _terms(P, q)
        if 2 * Phi.shape[1] > len(X):
            continue
        for lam in ridges:
            reg = lam * len(X) * np.eye(Phi.shape[1])
            reg[0, 0] = 0.0  # the intercept is not shrunk
            G = np.linalg.solve(Phi.T @ Phi + reg, Phi.T)
            H = Phi @ G
            resid = (Y - H @ Y) / (1 - np.diag(H))[:, None]
            err = float(np.sqrt(np.mean(resid**2)))
            loo[(q, lam)] = err
            if best is None or err < best[0]:
                best = (err, q, lam, G @ Y)
    if best is None:  # even the linear terms need two samples each
        raise ValueError(f"{kind}: {len(X)} samples are too few to fit its {k} principal components "
                         f"(at least {2 * (k + 1)} are needed)")
    _, q, lam, C = best
    fam = Family(kind, tuple(labels), tuple(names),
                 tuple(float(X[0, j]) if fixed_mask[j] else None for j in range(X.shape[1])),
                 tuple(map(float, X.min(0))), tuple(map(float, X.max(0))), tuple(map(float, mean)),
                 tuple(map(float, std)), tuple(map(tuple, rot.tolist())), tuple(map(float, scale)), q,
                 float(lam), tuple(map(tuple, C.tolist())), len(X))
    return fam, loo
