"""Response to contact: terrain contact (terrain.py), the impulses and overlap correction after a
step (impulses.py, overlap.py), and the implicit solve's penalty springs and their friction
(penalty.py, solve_friction.py).
"""
