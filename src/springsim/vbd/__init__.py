"""Vertex block descent (integrators/vbd.py): the spring graph and its colouring (graph.py), and
what one vertex's block gathers and solves (vertex.py)."""
