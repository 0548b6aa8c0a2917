"""Replaying a recording: `springsim play RUN.npz` in the polyscope viewer or, with ``--web``, in a
browser (viser). The timeline and what it shows are plain Python (timeline.py, recorded_model.py)
so that tests drive them without a window."""
