"""Headless Chromium for tests of Meshcat's standalone HTML replays.

Reusable by any test of a replay page (``import browser`` from a test in
``tests/sim/``)::

    browser.require_chromium()                       # skips without Chromium
    positions = browser.seek_positions(html, [0.0, 1.5, 3.0])   # {t: xyz}
    browser.screenshot(html, png, (1280, 720), time=0.0)
    assert browser.remote_loads(html_text) == []

How it works: a *copy* of the page gets a small script appended that waits
until the viewer has received the whole scene and its animation, pauses the
animation, seeks it (``viewer.animator.seek(t)``), reads a scene-tree node's
pose relative to the three.js scene (that is, in Drake's z-up world frame;
meshcat rotates its scene root into three.js' y-up frame) and writes the
results as JSON into a ``<pre id="drake-social-probe">`` element, which
``chromium --headless --dump-dom`` prints. Nothing is loaded from the network
(background networking is off and the page is a ``file://`` URL).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np

#: Where the Debian package ``chromium`` installs the browser.
CHROMIUM = "/usr/bin/chromium"
#: Scene-tree path of the robot's base body as drawn by
#: ``drake_social.sim.replay.add_visualizer``.
BASE_PATH = "/drake/illustration/mobile_manipulator/base"

_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-default-apps",
    "--disable-extensions",
    "--disable-sync",
    "--no-first-run",
    "--no-default-browser-check",
    "--hide-scrollbars",
    "--mute-audio",
]
_PROBE_ID = "drake-social-probe"
_PROBE = r"""
<script>
(function () {
  const times = __TIMES__;
  const path = __PATH__;
  const out = document.createElement("pre");
  out.id = "__ID__";
  out.style.display = "none";
  document.body.appendChild(out);
  function done(result) { out.textContent = JSON.stringify(result); document.title = "probe:done"; }
  let tries = 0;
  function probe() {
    tries += 1;
    const ready = typeof viewer !== "undefined" && viewer.animator.actions.length > 0;
    if (!ready) {
      if (tries > 400) { done({error: "no animation after " + tries + " tries"}); return; }
      setTimeout(probe, 25);
      return;
    }
    try {
      const animator = viewer.animator;
      animator.pause();
      const result = {duration: animator.duration, positions: [], frames: [], overlays: [], colours: []};
      let node = null;
      if (path !== null) {
        node = viewer.scene_tree;
        for (const name of path.split("/").filter(s => s.length > 0)) {
          if (!(name in node.children)) { done({error: "no scene-tree node " + name + " on " + path}); return; }
          node = node.children[name];
        }
      }
      for (const t of times) {
        animator.seek(t);
        if (node !== null) {
          viewer.scene.updateMatrixWorld(true);
          const M = node.object.matrixWorld.constructor;
          const X = new M().copy(viewer.scene.matrixWorld).invert().multiply(node.object.matrixWorld);
          result.positions.push([t, X.elements[12], X.elements[13], X.elements[14]]);
          // The node's yaw (about z) in the world, whether it and its parents
          // are visible, and its own x scale.
          let shown = true;
          for (let o = node.object; o; o = o.parent) shown = shown && o.visible;
          result.frames.push([t, Math.atan2(X.elements[1], X.elements[0]), shown, node.object.scale.x]);
          // The colour of the node's geometry (its "<object>" child's material), when it has one.
          const geometry = node.children["<object>"];
          if (geometry && geometry.object.material && geometry.object.material.color) {
            const c = geometry.object.material.color;
            result.colours.push([t, c.r, c.g, c.b]);
          }
        }
      }
      if ("drake_social" in viewer.scene_tree.children) {
        result.overlays = Object.keys(viewer.scene_tree.children["drake_social"].children);
      }
      viewer.set_dirty();
      viewer.render();
      done(result);
    } catch (e) {
      done({error: String(e) + "\n" + e.stack});
    }
  }
  probe();
})();
</script>
"""


def chromium_path() -> str | None:
    """The Chromium binary: ``$CHROMIUM`` if set, else :data:`CHROMIUM` or
    ``chromium`` on the PATH; None when none is installed."""
    for candidate in (os.environ.get("CHROMIUM"), CHROMIUM, shutil.which("chromium")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


def require_chromium() -> str:
    """The Chromium binary, or a pytest skip that says how to install it."""
    path = chromium_path()
    if path is None:
        import pytest

        pytest.skip(f"headless Chromium not installed ({CHROMIUM} missing): `apt-get install chromium` "
                    "(`make test` does it when run as root)")
    return path


def remote_loads(html: str) -> list[str]:
    """Remote (http/https or protocol-relative) URLs the page would load:
    ``<script src>``, ``<link href>``, ``<img src>``, ``<iframe src>``, CSS
    ``url(...)``, ``@import`` and ``fetch(...)`` of a literal URL.

    URLs that only appear as text inside the embedded meshcat.js (a WebXR
    asset path used only in a VR session, links in comments) are not loads.
    """
    remote = r"(?:https?:)?//[^\"'\s)>]+"
    patterns = [
        rf"<(?:script|img|iframe|source|video|audio|embed)\b[^>]*\bsrc\s*=\s*[\"']?({remote})",
        rf"<link\b[^>]*\bhref\s*=\s*[\"']?({remote})",
        rf"url\(\s*[\"']?({remote})",
        rf"@import\s+[\"']({remote})",
        rf"\bfetch\(\s*[\"'`]({remote})",
    ]
    return sorted({m for p in patterns for m in re.findall(p, html, flags=re.IGNORECASE)})


def _run(args: Sequence[str], timeout: float) -> subprocess.CompletedProcess:
    chromium = require_chromium()
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        cmd = [chromium, *_FLAGS, f"--user-data-dir={profile}", *args]
        # HOME in the profile: Chromium writes crash dumps and caches there.
        env = {**os.environ, "HOME": profile}
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    if proc.returncode != 0:
        raise RuntimeError(f"chromium failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr[-3000:]}")
    return proc


def _probed_copy(html_path: Path, folder: Path, times: Sequence[float], path: str | None) -> Path:
    """A copy of the page with the probe script before ``</body>``."""
    text = Path(html_path).read_text(encoding="utf-8")
    probe = (_PROBE.replace("__TIMES__", json.dumps([float(t) for t in times]))
             .replace("__PATH__", json.dumps(path)).replace("__ID__", _PROBE_ID))
    at = text.rfind("</body>")
    if at < 0:
        raise ValueError(f"{html_path}: no </body>; not a meshcat static page")
    copy = folder / f"probed_{Path(html_path).name}"
    copy.write_text(text[:at] + probe + text[at:], encoding="utf-8")
    return copy


def probe(html_path: str | os.PathLike, times: Sequence[float], path: str | None = BASE_PATH, *,
          budget_ms: int = 20000, timeout: float = 180.0) -> dict:
    """Runs the probe on a copy of the page and returns its JSON result.

    Returns:
        ``{"duration": s, "positions": [[t, x, y, z], ...], "frames": [[t,
        yaw, visible, scale_x], ...], "overlays": [...], "colours": [[t, r,
        g, b], ...]}`` (positions of ``path`` in Drake's world frame,
        metres; its yaw about z, radians; whether it and all its parents are
        visible; its own x scale; overlays: the children of
        ``/drake_social``; colours: its geometry's material colour, when
        it has a geometry).

    Raises:
        RuntimeError: Chromium failed, or the page's script reported an error.
    """
    with tempfile.TemporaryDirectory(prefix="replay-probe-") as tmp:
        copy = _probed_copy(Path(html_path), Path(tmp), times, path)
        proc = _run([f"--virtual-time-budget={budget_ms}", "--dump-dom", copy.resolve().as_uri()], timeout)
    match = re.search(rf'<pre id="{_PROBE_ID}"[^>]*>(.*?)</pre>', proc.stdout, flags=re.DOTALL)
    if match is None or not match.group(1):
        raise RuntimeError(f"{html_path}: the probe wrote nothing (WebGL or the page failed?)\n{proc.stderr[-3000:]}")
    result = json.loads(match.group(1).replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&"))
    if "error" in result:
        raise RuntimeError(f"{html_path}: {result['error']}")
    return result


def visible_at(html_path: str | os.PathLike, times: Sequence[float], path: str, **kwargs) -> list[bool]:
    """Whether the scene-tree node ``path`` (and all its parents) is visible
    with the page's animation seeked to each of ``times`` (seconds)."""
    return [bool(frame[2]) for frame in probe(html_path, times, path, **kwargs)["frames"]]


def seek_positions(html_path: str | os.PathLike, times: Sequence[float], path: str = BASE_PATH,
                   **kwargs) -> dict[float, np.ndarray]:
    """Positions (3,) in Drake's world frame, metres, of the scene-tree node
    ``path`` with the page's animation seeked to each of ``times`` (seconds)."""
    result = probe(html_path, times, path, **kwargs)
    return {float(t): np.array(xyz) for t, *xyz in result["positions"]}


def screenshot(html_path: str | os.PathLike, png_path: str | os.PathLike, size: tuple[int, int] = (1280, 720), *,
               time: float | None = 0.0, budget_ms: int = 20000, timeout: float = 180.0) -> Path:
    """A PNG of the page's first view, ``size`` = (width, height) pixels.

    Args:
        time: seek the animation there and pause it (seconds); None = let it
            play for the virtual time budget.
    """
    png_path = Path(png_path).resolve()
    with tempfile.TemporaryDirectory(prefix="replay-shot-") as tmp:
        page = Path(html_path) if time is None else _probed_copy(Path(html_path), Path(tmp), [time], None)
        _run([f"--virtual-time-budget={budget_ms}", f"--window-size={size[0]},{size[1]}",
              f"--screenshot={png_path}", page.resolve().as_uri()], timeout)
    if not png_path.is_file():
        raise RuntimeError(f"chromium wrote no screenshot {png_path}")
    return png_path
