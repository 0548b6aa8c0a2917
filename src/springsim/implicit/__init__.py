"""What backward Euler needs beyond the force kernels: the fixed block sparsity pattern of the
system matrix, its assembly from the spring and damper Jacobians, the contact and pin constraints,
ball-particle and surface contacts as penalty springs added matrix-free (penalty.py), the
surface contacts' friction against their push (solve_friction.py), and the filtered
conjugate-gradient solve (Baraff and Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998)."""
