"""What an artist sets: ``obj.springsim`` (role and material), ``scene.springsim`` (the run),
and the extension's preferences (which Python runs springsim)."""
import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

from . import presets

ROLES = [("NONE", "None", "not simulated by springsim"),
         ("CLOTH", "Cloth", "the mesh as it is, quads and triangles, as a cloth"),
         ("BODY", "Jelly body", "a lattice of springs filling the mesh (it needs an inside)"),
         ("COLLIDER", "Collider", "static or animated: what Blender evaluates at each frame")]
INTEGRATORS = [("implicit_euler", "Backward Euler", "implicit, stable at one step a frame"),
               ("vbd", "Vertex Block Descent", "backward Euler at a fixed cost a step; "
                "contact with colliders inside the solve"),
               ("symplectic_euler", "Symplectic Euler", "explicit; needs small steps"),
               ("midpoint", "Midpoint", "explicit second order; needs small steps"),
               ("rk4", "RK4", "explicit fourth order; needs small steps"),
               ("explicit_euler", "Explicit Euler", "explicit first order; needs tiny steps")]


def _apply_preset(settings, context):
    presets.apply(settings, settings.preset)


class ObjectSettings(bpy.types.PropertyGroup):
    role: EnumProperty(name="Role", items=ROLES, default="NONE")
    pin_group: StringProperty(
        name="Pin Group", description="vertex group: weight 1 pins a vertex to the animated "
        "mesh, a lower weight pins it with a spring of that share of the pin stiffness")
    pin_stiffness: FloatProperty(name="Pin Stiffness", default=1000.0, min=0.0,
                                 description="N/m of a weight-1 soft pin")
    pin_damping: FloatProperty(name="Pin Damping", default=1.0, min=0.0,
                               description="N s/m of a soft pin")
    thickness: FloatProperty(name="Thickness", default=0.01, min=0.0, unit="LENGTH",
                             description="m kept between this surface and others")
    friction: FloatProperty(name="Friction", default=0.4, min=0.0)
    restitution: FloatProperty(name="Restitution", default=0.0, min=0.0, max=1.0,
                               description="a collider's bounce")
    resolution: IntProperty(name="Resolution", default=64, min=8, max=1024,
                            description="a collider's distance-grid cells along its longest side")
    preset: EnumProperty(name="Preset", items=presets.ITEMS, default="COTTON",
                         update=_apply_preset)
    density: FloatProperty(name="Density", default=0.3, min=1e-6, description="kg/m²")
    stretch: FloatProperty(name="Stretch", default=5000.0, min=0.0, description="N/m")
    shear: FloatProperty(name="Shear", default=500.0, min=0.0, description="N/m")
    bend: FloatProperty(name="Bend", default=50.0, min=0.0, description="N/m")
    stretch_damping: FloatProperty(name="Stretch Damping", default=0.5, min=0.0)
    shear_damping: FloatProperty(name="Shear Damping", default=0.05, min=0.0)
    bend_damping: FloatProperty(name="Bend Damping", default=0.005, min=0.0)
    particles: IntProperty(name="Particles", default=2000, min=8,
                           description="about how many lattice particles fill a jelly body")
    particle_mass: FloatProperty(name="Particle Mass", default=1.0, min=1e-9,
                                 description="kg per lattice particle of a jelly body")
    spring_ks: FloatProperty(name="Spring Stiffness", default=2000.0, min=0.0,
                             description="N/m of a jelly body's springs")
    spring_kd: FloatProperty(name="Spring Damping", default=60.0, min=0.0,
                             description="N s/m of a jelly body's springs")


class SceneSettings(bpy.types.PropertyGroup):
    integrator: EnumProperty(name="Integrator", items=INTEGRATORS, default="implicit_euler")
    substeps: IntProperty(name="Steps per Frame", default=1, min=1, max=10000)
    use_frame_range: BoolProperty(name="Own Frame Range", default=False)
    frame_start: IntProperty(name="Start", default=1)
    frame_end: IntProperty(name="End", default=250)
    gravity: FloatVectorProperty(name="Gravity", default=(0.0, 0.0, -9.81), subtype="ACCELERATION",
                                 size=3)
    self_collision: BoolProperty(name="Self Collision", default=True)
    use_air: BoolProperty(name="Air", default=False,
                          description="still air resists motion even without a Wind field")
    air_density: FloatProperty(name="Air Density", default=1.2, min=0.0)
    air_drag: FloatProperty(name="Air Drag", default=1.0, min=0.0)
    last_message: StringProperty(name="Last Message", options={"SKIP_SAVE"})


class Preferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    python_path: StringProperty(
        name="springsim Python", subtype="FILE_PATH",
        description="the Python that has springsim installed (empty: the one that wrote the "
                    "extension's zip)")

    def draw(self, context):
        self.layout.prop(self, "python_path")


CLASSES = (ObjectSettings, SceneSettings, Preferences)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.springsim = PointerProperty(type=ObjectSettings)
    bpy.types.Scene.springsim = PointerProperty(type=SceneSettings)


def unregister():
    del bpy.types.Scene.springsim
    del bpy.types.Object.springsim
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)


def preferred_python(context) -> str:
    addon = context.preferences.addons.get(__package__)
    return addon.preferences.python_path if addon is not None and addon.preferences else ""
