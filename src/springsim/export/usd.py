"""USD (Pixar's Universal Scene Description, with Pixar's own ``usd-core`` bindings).

One stage: ``/take`` (the default prim) holding ``bodies/`` (a UsdGeom.Mesh per body surface with
time-sampled points and extents), ``balls/`` (a UsdGeom.Sphere per ball with its radius and a
time-sampled translate) and ``terrains/`` (meshes, with time-sampled points where a terrain
moves or deforms). Frame k of the take is time code
start_frame + k (Blender and Houdini number frames from 1); the stage's timeCodesPerSecond (and framesPerSecond) is the recording's fps, its start and end
time codes are the first and last frame, its up axis is Y (springsim's) and a unit is 1 m. The
extension picks the encoding: .usda text, .usdc binary (crate), .usd binary.
"""
import numpy as np

from .. import signals
from ..errors import require
from ..render import colors
from .geometry import body_pieces, terrain_meshes, unique_names
from ..safe_files import staged_path

EXTENSIONS = (".usd", ".usda", ".usdc")
DESCRIPTION = "USD stage: animated body meshes, balls as spheres, terrains (moving ones animated)"
INSTALL = "pip install 'springsim[export]' (usd-core)"


def outputs(path) -> list:
    return [path]


def check_available() -> None:
    try:
        _import_usd()
    except ImportError:
        require(False, "format", "usd", f"needs Pixar's usd-core: {INSTALL}")


def _import_usd() -> None:
    """Load usd-core's modules. Its C++ import code catches an exception raised while it runs
    and prints a warning, so Ctrl-C there would be lost: the signal waits for the imports."""
    with signals.deferred():
        import pxr.Gf
        import pxr.Tf
        import pxr.Usd
        import pxr.UsdGeom
        import pxr.Vt  # noqa: F401


def write(take, path) -> list:
    """Write ``take`` to the USD file ``path`` (its suffix picks the encoding)."""
    _import_usd()
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(take.fps)
    stage.SetFramesPerSecond(take.fps)
    stage.SetStartTimeCode(take.start_frame)
    stage.SetEndTimeCode(take.start_frame + take.frame_count - 1)
    root = UsdGeom.Xform.Define(stage, "/take")
    stage.SetDefaultPrim(root.GetPrim())
    root.GetPrim().SetCustomDataByKey("springsim:scene", take.name)
    _bodies(stage, take)
    _balls(stage, take)
    _terrains(stage, take)
    with staged_path(path) as staged:
        require(stage.GetRootLayer().Export(str(staged)), "export", str(path),
                "USD could not write this file")
    return [path]


def _bodies(stage, take) -> None:
    from pxr import Gf, UsdGeom, Vt

    UsdGeom.Scope.Define(stage, "/take/bodies")
    pieces = body_pieces(take.layout, take.positions[0])
    names = unique_names(_identifier(piece.name) for piece in pieces)
    for number, (piece, name) in enumerate(zip(pieces, names)):
        mesh = _static_mesh(stage, f"/take/bodies/{name}", piece.triangles,
                            not piece.closed)
        color = colors.BODY_COLORS[number % len(colors.BODY_COLORS)]
        mesh.CreateDisplayColorAttr([Gf.Vec3f(*color)])
        points, extent = mesh.CreatePointsAttr(), mesh.CreateExtentAttr()
        vertices = piece.vertices(take.positions).astype(np.float32)   # (F, V, 3)
        low, high = vertices.min(axis=1), vertices.max(axis=1)
        for frame in range(take.frame_count):
            code = take.start_frame + frame
            points.Set(Vt.Vec3fArray.FromNumpy(vertices[frame]), code)
            extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([low[frame], high[frame]])), code)


def _balls(stage, take) -> None:
    from pxr import Gf, UsdGeom

    layout = take.layout
    if not len(layout.ball_particles):
        return
    UsdGeom.Scope.Define(stage, "/take/balls")
    centres = take.positions[:, layout.ball_particles].astype(float)   # (F, N, 3)
    for number, radius in enumerate(layout.ball_radii):
        sphere = UsdGeom.Sphere.Define(stage, f"/take/balls/ball_{number}")
        sphere.CreateRadiusAttr(float(radius))
        sphere.CreateExtentAttr([Gf.Vec3f(-float(radius)), Gf.Vec3f(float(radius))])
        sphere.CreateDisplayColorAttr([Gf.Vec3f(*colors.BALL_COLOR)])
        translate = sphere.AddTranslateOp()
        for frame, centre in enumerate(centres[:, number].tolist()):
            translate.Set(Gf.Vec3d(*centre), take.start_frame + frame)


def _terrains(stage, take) -> None:
    from pxr import Gf, Usd, UsdGeom, Vt

    meshes = terrain_meshes(take.layout, take.positions)
    if not meshes:
        return
    UsdGeom.Scope.Define(stage, "/take/terrains")
    for name, vertices, triangles, terrain in meshes:
        mesh = _static_mesh(stage, f"/take/terrains/{_identifier(name)}", triangles, False)
        mesh.CreateDisplayColorAttr([Gf.Vec3f(*colors.TERRAIN_COLOR)])
        points, extent = mesh.CreatePointsAttr(), mesh.CreateExtentAttr()
        # a terrain that moves or deforms has its points at every frame (a still one: once)
        frames = range(take.frame_count) if terrain.moves() else [None]
        for frame in frames:
            here = vertices if frame is None else terrain.vertices_at(vertices, take.time[frame])
            here = np.asarray(here, np.float32)
            code = Usd.TimeCode.Default() if frame is None else take.start_frame + frame
            points.Set(Vt.Vec3fArray.FromNumpy(here), code)
            extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([here.min(axis=0), here.max(axis=0)])),
                       code)


def _static_mesh(stage, path: str, triangles: np.ndarray, double_sided: bool):
    """A mesh prim with its triangles (no subdivision: these are the simulated faces)."""
    from pxr import UsdGeom, Vt

    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(triangles), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(
        np.ascontiguousarray(triangles, np.int32).ravel()))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateDoubleSidedAttr(double_sided)
    return mesh


def _identifier(name: str) -> str:
    from pxr import Tf

    return Tf.MakeValidIdentifier(name)
