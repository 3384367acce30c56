"""
3D finger and the rod: ``fe-beam solid`` and ``fe-beam compare``
================================================================

The finger as a 3D hyperelastic solid (gmsh mesh, neo-Hookean, the tendon a cable embedded in
the mesh, anchored on the tip face) with the 1D rod alongside, then a tension sweep of the solid
against rods with different section laws. The mesh is coarse (10 mm elements: one across the
tip) so that the page builds fast; the example's 5 mm is closer to converged.
"""

# sphinx_gallery_thumbnail_number = 2


from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("solid_compare")

# %%
solid = fe_beam("solid", "finger_solid.toml", "solid", "solid.mesh_size=0.01")
last = solid["steps"][-1]
print(f"{solid['dofs']} dofs; tip angle {last['tip']['theta']:.4f} rad at "
      f"{last['tensions'][0]} N; largest bulk principal stretch "
      f"{last['max_principal_stretch_bulk']:.4f}")
show("solid", "backbone.png")

# %%
# The sweep (``[compare] tensions``, here 1 and 2 N; laws of the rod: non-standard and Reissner):
compare = fe_beam("compare", "finger_solid.toml", "compare", "solid.mesh_size=0.01",
                  "compare.tensions=[1.0, 2.0]", 'compare.laws=["nonstandard", "reissner"]')
for row in compare["table"]:
    print(f"{row['tension']} N: 3D tip angle {row['solid']['tip']['theta']:.4f}; " + ", ".join(
        f"{law} d/L = {rod['distance_over_L']:.2%}" for law, rod in row["rod"].items()))
show("compare", "backbones.png")

# %%
show("compare", "tip_vs_tension.png")
