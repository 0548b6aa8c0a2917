"""A cloth's material: mass per area and stiffness per unit strain, turned into particle masses
and per-spring constants from the rest geometry, so that one cloth behaves alike at any
resolution.

- Masses: each face's area times ``density``, shared equally among its corners.
- Springs: a spring of rest length L carrying the area A_s gets ``k = stiffness * A_s / L^2``
  (and ``kd = damping * A_s / L^2``). Both are ratios of areas to squared lengths, so refining a
  mesh leaves them unchanged while the masses shrink with the faces: the same sheet, better
  resolved.

  - structural: A_s sums, over the faces beside the edge, the triangle's area (a triangular
    network of springs k then has the membrane modulus 2 k / sqrt(3) of an equilateral mesh) or
    half the quad's (a square grid's springs then carry ``stretch`` exactly);
  - shear, a quad's diagonal: twice the quad's area (a square grid's diagonals then carry
    ``shear``, the modulus of a square's shearing);
  - bend: L^2, so each bend spring has ``k = bend`` (a bend spring spans two cells at any
    resolution).
"""
from dataclasses import dataclass

import numpy as np

from ..errors import is_finite, require
from ..springs import SpringKind
from .sheet_mesh import corner_count, face_edges, faces_of, polygon_areas


@dataclass
class ClothMaterial:
    """Mass per area (kg/m^2) and stiffness (N/m) and damping (N s/m) per unit strain.
    Defaults: a light cotton-like sheet."""

    density: float = 0.3
    stretch: float = 5000.0
    shear: float = 500.0
    bend: float = 50.0
    stretch_damping: float = 0.5
    shear_damping: float = 0.05
    bend_damping: float = 0.005

    def validate(self, key: str) -> None:
        require(is_finite(self.density) and self.density > 0, f"{key}.density", self.density,
                "must be > 0 kg/m^2")
        for name in ("stretch", "shear", "bend", "stretch_damping", "shear_damping",
                     "bend_damping"):
            value = getattr(self, name)
            require(is_finite(value) and value >= 0, f"{key}.{name}", value,
                    "must be >= 0 " + ("N s/m" if name.endswith("damping") else "N/m"))

    def per_kind(self, kind: SpringKind) -> tuple[float, float]:
        name = {SpringKind.STRUCTURAL: "stretch", SpringKind.SHEAR: "shear",
                SpringKind.BEND: "bend"}[SpringKind(kind)]
        return getattr(self, name), getattr(self, f"{name}_damping")


def lumped_masses(positions: np.ndarray, faces: np.ndarray, density: float) -> np.ndarray:
    """(n,) kg: each face's mass shared equally among its corners."""
    share = density * polygon_areas(positions, faces) / corner_count(faces)
    masses = np.zeros(len(positions))
    valid = faces >= 0
    np.add.at(masses, faces[valid], np.broadcast_to(share[:, None], faces.shape)[valid])
    return masses


def spring_areas(positions, faces, springs: np.ndarray, kinds: np.ndarray) -> np.ndarray:
    """(S,) m^2: the area each spring carries (module doc)."""
    n = np.int64(len(positions))
    code = np.minimum(springs[:, 0], springs[:, 1]).astype(np.int64) * n + \
        np.maximum(springs[:, 0], springs[:, 1])
    length = np.linalg.norm(positions[springs[:, 0]] - positions[springs[:, 1]], axis=1)
    areas = length ** 2                                         # bend: k = stiffness
    face_area, count = polygon_areas(positions, faces), corner_count(faces)
    # structural: a triangle gives its area to each edge, a larger face half of it
    edges = face_edges(faces)
    share = np.repeat(np.where(count == 3, face_area, 0.5 * face_area), count)
    _add_by_code(areas, kinds == SpringKind.STRUCTURAL, code, edges, share, n)
    # shear: a quad gives twice its area to each diagonal
    quads = faces_of(faces, 4)
    diagonals = np.concatenate([quads[:, [0, 2]], quads[:, [1, 3]]])
    _add_by_code(areas, kinds == SpringKind.SHEAR, code, diagonals,
                 np.tile(2.0 * face_area[count == 4], 2), n)
    return areas


def _add_by_code(areas, members, code, pairs, share, n) -> None:
    """Set the members' areas to the sum of ``share`` over the ``pairs`` that are those springs."""
    pair_code = np.minimum(pairs[:, 0], pairs[:, 1]).astype(np.int64) * n + \
        np.maximum(pairs[:, 0], pairs[:, 1])
    rows = np.flatnonzero(members)
    order = np.argsort(code[rows])
    position = np.searchsorted(code[rows][order], pair_code)
    position = np.minimum(position, len(rows) - 1)
    found = code[rows][order][position] == pair_code if len(rows) else np.zeros(0, bool)
    total = np.zeros(len(rows))
    np.add.at(total, order[position[found]], share[found])
    areas[rows] = total


def material_constants(material: ClothMaterial, positions, faces, springs, kinds) -> np.ndarray:
    """(S, 2) each spring's (ks, kd) from the material and the rest geometry."""
    areas = spring_areas(positions, faces, springs, kinds)
    length = np.linalg.norm(positions[springs[:, 0]] - positions[springs[:, 1]], axis=1)
    scale = areas / length ** 2
    table = np.zeros((max(SpringKind) + 1, 2))
    for kind in (SpringKind.STRUCTURAL, SpringKind.SHEAR, SpringKind.BEND):
        table[kind] = material.per_kind(kind)
    return table[kinds] * scale[:, None]
