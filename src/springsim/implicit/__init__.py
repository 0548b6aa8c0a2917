"""What backward Euler needs beyond the force kernels: the fixed block sparsity pattern of the
system matrix, its assembly from the spring and damper Jacobians, the contact and pin constraints,
and the filtered conjugate-gradient solve (Baraff and Witkin, "Large Steps in Cloth Simulation",
SIGGRAPH 1998)."""
