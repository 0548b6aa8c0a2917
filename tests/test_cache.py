"""The compiled-kernel cache: other versions' folders are deleted once unused for STALE_DAYS,
the current one and recently used ones are kept."""
import os
import time

from springsim._jit import STALE_DAYS, remove_stale_caches


def test_only_other_versions_unused_for_stale_days_are_deleted(tmp_path):
    now = time.time()
    day = 86400
    ages = {"numba-current": 400, "numba-old": STALE_DAYS + 1, "numba-recent": STALE_DAYS - 1,
            "not-a-cache": 400}
    for name, age in ages.items():
        folder = tmp_path / name
        (folder / "sub").mkdir(parents=True)
        (folder / "sub" / "kernel.nbc").write_bytes(b"x")
        os.utime(folder, (now - age * day, now - age * day))
    deleted = remove_stale_caches(tmp_path, keep=tmp_path / "numba-current", now=now)
    assert deleted == [tmp_path / "numba-old"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not-a-cache", "numba-current",
                                                          "numba-recent"]
