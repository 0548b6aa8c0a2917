"""The springsim panels: an object's role and material in the Physics tab, the run's settings
and the Simulate / Free / Export buttons in the Scene tab (and under the object's panel)."""
import bpy


class PHYSICS_PT_springsim(bpy.types.Panel):
    bl_label = "springsim"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context):
        layout, obj = self.layout, context.object
        settings = obj.springsim
        layout.use_property_split = True
        layout.prop(settings, "role")
        if settings.role == "NONE":
            return
        if settings.role == "COLLIDER":
            for name in ("friction", "restitution", "resolution"):
                layout.prop(settings, name)
        else:
            layout.prop(settings, "preset")
            layout.prop(settings, "thickness")
            layout.prop(settings, "friction")
        if settings.role == "CLOTH":
            column = layout.column(align=True)
            for name in ("density", "stretch", "shear", "bend", "stretch_damping",
                         "shear_damping", "bend_damping"):
                column.prop(settings, name)
            layout.prop_search(settings, "pin_group", obj, "vertex_groups")
            if settings.pin_group:
                layout.prop(settings, "pin_stiffness")
                layout.prop(settings, "pin_damping")
        elif settings.role == "BODY":
            column = layout.column(align=True)
            for name in ("particles", "particle_mass", "spring_ks", "spring_kd"):
                column.prop(settings, name)
        buttons(layout)


class SCENE_PT_springsim(bpy.types.Panel):
    bl_label = "springsim"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "scene"

    def draw(self, context):
        layout, settings = self.layout, context.scene.springsim
        layout.use_property_split = True
        layout.prop(settings, "integrator")
        layout.prop(settings, "substeps")
        layout.prop(settings, "use_frame_range")
        if settings.use_frame_range:
            row = layout.row(align=True)
            row.prop(settings, "frame_start")
            row.prop(settings, "frame_end")
        layout.prop(settings, "gravity")
        layout.prop(settings, "self_collision")
        layout.prop(settings, "use_air")
        if settings.use_air:
            layout.prop(settings, "air_density")
            layout.prop(settings, "air_drag")
        buttons(layout)
        layout.operator("springsim.export_scene", icon="EXPORT")
        if settings.last_message:
            layout.label(text=settings.last_message)


def buttons(layout) -> None:
    row = layout.row(align=True)
    row.operator("springsim.simulate", icon="PLAY")
    row.operator("springsim.free", icon="TRASH")


CLASSES = (PHYSICS_PT_springsim, SCENE_PT_springsim)
