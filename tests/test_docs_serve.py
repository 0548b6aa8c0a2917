"""`springsim docs` builds the site and serves it: started on a free port, it prints its address,
answers with the built pages, and stops on Ctrl-C."""
import signal
import subprocess
import sys
import urllib.request

import pytest

from test_docs_examples import environment


@pytest.mark.slow   # builds the site, then serves it
def test_docs_serves_the_built_site(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra (./test.sh installs it)")
    site = tmp_path / "site"
    server = subprocess.Popen([sys.executable, "-m", "springsim", "docs", "--port", "0",
                               "--site-dir", str(site)], cwd=tmp_path, env=environment(tmp_path),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()   # printed once the site is built and the port bound
        assert "serving" in line, line + server.stderr.read() if server.poll() is not None else line
        url = line.split(" at ", 1)[1].split()[0]
        assert url.startswith("http://127.0.0.1:")
        index = urllib.request.urlopen(url, timeout=30).read().decode()
        assert "<html" in index and "springsim" in index
        reference = urllib.request.urlopen(url + "guide/scene-reference/", timeout=30).read()
        assert b"bodies.N.particles_per_edge" in reference
        assert (site / "index.html").is_file()
    finally:
        server.send_signal(signal.SIGINT)
        code = server.wait(timeout=30)
        server.stdout.close()
        server.stderr.close()
    assert code == 130   # Ctrl-C, as every command reports it


def test_docs_refuses_a_bad_port_in_one_line(tmp_path):
    done = subprocess.run([sys.executable, "-m", "springsim", "docs", "--port", "70000",
                           "--site-dir", str(tmp_path / "site")], env=environment(tmp_path),
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip() == ("springsim docs: --port = 70000: must be a TCP port in "
                                   "[0, 65535]")
    assert not (tmp_path / "site").exists()   # checked before anything is built
