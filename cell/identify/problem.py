"""The identification problem: throws as arrays, the two parameter blocks, their
residuals and Jacobians.

Stage 1 block (η_ee): the identifiable end-effector parameters
`EndEffectorParams.IDENTIFIABLE`, each divided by a fixed scale so that the
solver sees numbers of order one. The band law and the band geometry enter the
landing only through the push f_o of each throw, so their Jacobian is the chain
dp/df_o · df_o/dθ: df_o/dθ is analytic (eqs. 3.1-3.9) and dp/df_o costs one
extra model evaluation for all throws at once (a throw's landing depends on its
own push only). The push duration Δt costs one more. Three evaluations per
Jacobian instead of nine.

Stage 2 block (η_o): per object a mass factor and extent factors (multiplying
the start values), tied by shape so that a cube stays a cube (cube and sphere:
one extent factor; cylinder: diameter and height; cuboid and mesh: three). A
throw depends on its own object's factors only, so the Jacobian is block
diagonal and a perturbation of factor slot s of every object at once gives
column s of every block: at most four evaluations for all objects.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from cell.errors import InvalidInput, plural
from cell.log.table import ThrowTable
from cell.model.band import band_angle, band_stretch
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, predict_landing
from cell.synth import NoiseModel

__all__ = [
    "EE_NAMES",
    "EE_SCALE",
    "ThrowData",
    "ee_bounds",
    "ee_from_vector",
    "ee_to_vector",
    "factor_names",
    "push_jacobian",
    "size_slots",
    "whitening",
]

log = logging.getLogger(__name__)

EE_NAMES = EndEffectorParams.IDENTIFIABLE  # ("Ke3", "Ke2", "Ke1", "C", "r_r", "l1", "phi", "dt")
# Typical magnitudes [SI] the stage-1 vector is divided by (the reference values; C: 1 N).
EE_SCALE = np.array([400.0, 150.0, 114.6, 1.0, 0.010, 0.030, np.pi / 2, 0.012])


def ee_to_vector(ee: EndEffectorParams) -> np.ndarray:
    """The stage-1 vector: identifiable parameters divided by EE_SCALE."""
    return np.array([getattr(ee, k) for k in EE_NAMES]) / EE_SCALE


def ee_from_vector(z: np.ndarray, base: EndEffectorParams) -> EndEffectorParams:
    """`base` with the identifiable parameters taken from a stage-1 vector."""
    return replace(
        base, **{k: float(v) for k, v in zip(EE_NAMES, np.asarray(z) * EE_SCALE, strict=True)}
    )


def ee_bounds(start: EndEffectorParams) -> tuple[np.ndarray, np.ndarray]:
    """Physical bounds of the stage-1 vector around a start point.

    Band coefficients stay ≥ 0 (a stiffening band; Ke1 > 0) and within 5× the
    larger of start and reference; the offset C within ±5 N; roller radius and
    clamp length within 0.5-2× the start; the wrap angle within [π/4, π]; the push
    duration within 0.25-4× the start.
    """
    s = ee_to_vector(start)
    lo = np.array(
        [0.0, 0.0, 0.2 * s[2], -5.0, 0.5 * s[4], 0.5 * s[5], 0.5, 0.25 * s[7]],
    )
    hi = np.array(
        [
            5 * max(s[0], 1.0),
            5 * max(s[1], 1.0),
            5 * max(s[2], 1.0),
            5.0,
            2 * s[4],
            2 * s[5],
            2.0,
            4 * s[7],
        ]
    )
    return lo, hi


def push_jacobian(batch: ThrowBatch, ee: EndEffectorParams) -> np.ndarray:
    """∂f_o/∂θ [N per unit of the stage-1 vector], shape (n, 8); the Δt column is 0.

    f_o = 2 f_e(ΔL) cos α with ΔL = l1 + r_r φ + d/2 + l2 - L0; α does not depend
    on θ. Zero where the band is slack or its force clamps at 0.
    """
    dl = np.asarray(band_stretch(batch.stroke, batch.size[:, 0], ee))
    cos_a = np.cos(np.asarray(band_angle(batch.stroke, batch.size[:, 0], ee)))
    f = ((ee.Ke3 * dl + ee.Ke2) * dl + ee.Ke1) * dl + ee.C
    active = (dl > 0) & (f > 0)
    dfe_ddl = (3 * ee.Ke3 * dl + 2 * ee.Ke2) * dl + ee.Ke1
    cols = [
        dl**3,  # Ke3
        dl**2,  # Ke2
        dl,  # Ke1
        np.ones_like(dl),  # C
        dfe_ddl * ee.phi,  # r_r
        dfe_ddl,  # l1
        dfe_ddl * ee.r_r,  # phi
        np.zeros_like(dl),  # dt
    ]
    jac = 2 * cos_a[:, None] * np.stack(cols, axis=1) * EE_SCALE[None, :]
    return np.where(active[:, None], jac, 0.0)


def size_slots(shape: str) -> list[tuple[int, ...]]:
    """The extent groups one factor each scales, by shape (indices into size x, y, z)."""
    if shape in ("cube", "sphere"):
        return [(0, 1, 2)]
    if shape == "cylinder":
        return [(0, 1), (2,)]
    return [(0,), (1,), (2,)]


def factor_names(shape: str) -> list[str]:
    """Names of an object's factor slots: mass, then its extent groups."""
    groups = {
        "cube": ["size"],
        "sphere": ["size"],
        "cylinder": ["diameter", "height"],
    }.get(shape, ["x", "y", "z"])
    return ["mass", *groups]


def whitening(
    release_xy: np.ndarray, landing_xy: np.ndarray, azimuth: np.ndarray, noise: NoiseModel
) -> np.ndarray:
    """Per throw the 2x2 map taking a landing residual [m, W] to units of its noise σ.

    The documented noise (`cell.synth.NoiseModel`) is Gaussian in the throw's horizontal
    frame with σ_along and σ_across growing with the reach: row 1 of the map is the unit
    along-throw direction over σ_along, row 2 the across direction over σ_across, so the
    sum of squares of mapped residuals is -2 log-likelihood (up to a constant). The reach
    and direction are those of `landing_xy` (the model's current prediction), from the
    release; where it is not finite or shorter than 1 mm, the azimuth and a reach of 0.

    Returns:
        shape (n, 2, 2) [1/m].
    """
    d = np.asarray(landing_xy, float) - np.asarray(release_xy, float)
    ok = np.all(np.isfinite(d), axis=1)
    reach = np.where(ok, np.hypot(d[:, 0], d[:, 1]), 0.0)
    az = np.c_[np.cos(azimuth), np.sin(azimuth)]
    use = ok & (reach > 1e-3)
    along = np.where(
        use[:, None], np.where(ok[:, None], d, 0.0) / np.maximum(reach, 1e-3)[:, None], az
    )
    across = np.c_[-along[:, 1], along[:, 0]]
    s_along, s_across = noise.sigma(reach)
    return np.stack([along / s_along[:, None], across / s_across[:, None]], axis=1)


@dataclass
class ThrowData:
    """Throws prepared for identification (only those with stroke and landing).

    Attributes:
        batch: the throws with the start η_o.
        observed: observed landing points [m, W], shape (n, 2).
        object_ids: the distinct object ids, sorted.
        obj: index into object_ids per throw, shape (n,).
        start_objects: start η_o per object id.
        rows: indices of these throws in the source table.
        whiten: per throw the map of a residual into units of its noise σ (`whitening`),
            shape (n, 2, 2); None = residuals in metres (unweighted least squares).
    """

    batch: ThrowBatch
    observed: np.ndarray
    object_ids: list[str]
    obj: np.ndarray
    start_objects: dict[str, ObjectParams]
    rows: np.ndarray
    whiten: np.ndarray | None = None

    @classmethod
    def from_table(
        cls, table: ThrowTable, start_objects: dict[str, ObjectParams] | None = None
    ) -> ThrowData:
        """Prepare a log's usable throws.

        Args:
            table: the log.
            start_objects: start η_o by object id; an id not given starts from the
                mass and extents its first row logs.

        Raises:
            InvalidInput: no throw with both a stroke and an observed landing.
        """
        stroke = table.num("stroke_m")
        landed = table.landed
        ok = np.isfinite(stroke) & np.all(np.isfinite(landed), axis=1)
        if not ok.any():
            raise InvalidInput(
                f"{table.path or 'throw log'}: no throw has both stroke_m and landed_x_m/"
                "landed_y_m; identification needs the stroke and the observed landing"
            )
        if not ok.all():
            log.info("%s without stroke or landing left out", plural(int((~ok).sum()), "throw"))
        rows = np.flatnonzero(ok)
        sub = table.take(rows)
        ids = sub.text("object_id")
        objects: dict[str, ObjectParams] = {}
        mass, shape = sub.num("mass_kg"), sub.text("shape")
        size = np.stack([sub.num("size_x_m"), sub.num("size_y_m"), sub.num("size_z_m")], -1)
        first: dict[str, int] = {}
        for i, oid in enumerate(ids):
            if oid in objects:
                j = first[oid]
                if shape[i] != shape[j] or mass[i] != mass[j] or np.any(size[i] != size[j]):
                    log.warning(
                        "object %s: row %d logs another shape, mass or size than row %d; "
                        "identification starts from the first",
                        oid,
                        int(rows[i]) + 1,
                        int(rows[j]) + 1,
                    )
                    first[oid] = i  # warn once per change, not per row
                continue
            first[oid] = i
            given = (start_objects or {}).get(oid)
            if given is not None:
                objects[oid] = replace(given, name=oid)
            else:
                objects[oid] = ObjectParams(
                    shape=shape[i], mass=float(mass[i]), size=tuple(size[i]), name=oid
                )
        object_ids = sorted(objects)
        obj = np.array([object_ids.index(o) for o in ids], dtype=int)
        batch = sub.to_batch(objects=objects)
        return cls(
            batch=batch,
            observed=sub.landed,
            object_ids=object_ids,
            obj=obj,
            start_objects=objects,
            rows=rows,
        )

    def weigh(self, batch: ThrowBatch, ee: EndEffectorParams, noise: NoiseModel) -> None:
        """Set the residual weights from the landings these parameters predict.

        The weights are held while a stage solves (iteratively reweighted least squares:
        the fixed point is the maximum-likelihood fit, the spread following the fit's
        own reach rather than the noisy observed one, which would favour short throws).
        """
        land = predict_landing(batch, ee, strict=False, check_stroke=False).xy
        land = np.where(np.isfinite(land).all(axis=1)[:, None], land, self.observed)
        self.whiten = whitening(batch.position[:, :2], land, batch.azimuth, noise)

    def whitened(self, res: np.ndarray) -> np.ndarray:
        """Residuals [m] in units of their noise σ (unchanged when no weights are set)."""
        if self.whiten is None:
            return res
        return np.einsum("nij,nj->ni", self.whiten, res)

    def wres(
        self, batch: ThrowBatch, ee: EndEffectorParams, push: np.ndarray | None = None
    ) -> np.ndarray:
        """`residual` in units of the noise σ, shape (n, 2)."""
        return self.whitened(self.residual(batch, ee, push))

    def take(self, rows: np.ndarray) -> ThrowData:
        """These throws only (rows index this data; objects and factor layout kept)."""
        return replace(
            self,
            batch=self.batch.take(rows),
            observed=self.observed[rows],
            obj=self.obj[rows],
            rows=self.rows[rows],
            whiten=None if self.whiten is None else self.whiten[rows],
        )

    def __len__(self) -> int:
        return len(self.batch)

    # -- stage 2 parameterisation ------------------------------------------------
    def factor_layout(self) -> list[list[tuple[int, ...]]]:
        """Per object, its factor slots: slot 0 = mass (), then the extent groups."""
        return [[()] + size_slots(self.start_objects[o].shape) for o in self.object_ids]

    def factor_columns(self) -> tuple[np.ndarray, int]:
        """Column of (object, slot) in the stage-2 vector, -1 where absent; and its length."""
        layout = self.factor_layout()
        col = -np.ones((len(layout), 4), dtype=int)
        k = 0
        for j, slots in enumerate(layout):
            for s in range(len(slots)):
                col[j, s] = k
                k += 1
        return col, k

    def objects_from_factors(self, factors: np.ndarray) -> dict[str, ObjectParams]:
        """η_o per object id from a stage-2 vector of factors."""
        col, _ = self.factor_columns()
        out = {}
        for j, (oid, slots) in enumerate(zip(self.object_ids, self.factor_layout(), strict=True)):
            o = self.start_objects[oid]
            size = list(o.size)
            for s, group in enumerate(slots[1:], start=1):
                for axis in group:
                    size[axis] = o.size[axis] * float(factors[col[j, s]])
            out[oid] = replace(o, mass=o.mass * float(factors[col[j, 0]]), size=tuple(size))  # type: ignore[arg-type]
        return out

    def batch_with(self, objects: dict[str, ObjectParams]) -> ThrowBatch:
        """The throws with these η_o (no re-validation: factors are bounded > 0)."""
        m = np.array([objects[o].mass for o in self.object_ids])
        s = np.array([objects[o].size for o in self.object_ids])
        return replace(self.batch, mass=m[self.obj], size=s[self.obj])

    # -- model ---------------------------------------------------------------------
    def residual(
        self, batch: ThrowBatch, ee: EndEffectorParams, push: np.ndarray | None = None
    ) -> np.ndarray:
        """Predicted minus observed landing [m], shape (n, 2).

        A throw the model says never lands (not possible with a floor below the
        release) counts as landing under its release point, so the residual stays
        finite and large.
        """
        land = predict_landing(batch, ee, strict=False, check_stroke=False, push=push)
        xy = land.xy
        bad = ~np.isfinite(xy).all(axis=1)
        if bad.any():
            xy = np.where(bad[:, None], batch.position[:, :2], xy)
        return xy - self.observed
