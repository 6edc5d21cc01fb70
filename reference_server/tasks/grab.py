"""<surveillance><grab>: the scan as ``NAME.dat`` and a rendered top-down image as ``NAME.jpg`` (E-TASK-013).

Rules: pure functions of their inputs (scan points in platform coordinates, mm, as CMD_GET_STATUS reports
them); only ``write_grab`` touches the file system. The image is what a simulated camera above the platform
would see: 25 mm per pixel, the platform at the centre heading up, 1 m range rings, the scan points.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

SIZE = 400  # px
MM_PER_PX = 25.0
Point = tuple[float, float]


def scan_text(points: Sequence[Point], pose: tuple[float, float, float], now: float) -> str:
    """The .dat file: comment lines, then one point per line "x y" (mm, platform coordinates)."""
    x, y, angle = pose
    lines = [
        "# pltf scan grab (E-TASK-013): one point per line, x y in mm, platform coordinates",
        f"# time {now:.3f} s, pose x {x:.0f} mm y {y:.0f} mm angle {angle:.3f} deg, {len(points)} points",
    ]
    lines += [f"{px:.0f} {py:.0f}" for px, py in points]
    return "\n".join(lines) + "\n"


def render_jpeg(points: Sequence[Point]) -> bytes:
    """A top-down image: platform at the centre, its x axis up; points as dots."""
    img = Image.new("RGB", (SIZE, SIZE), (245, 245, 240))
    draw = ImageDraw.Draw(img)
    c = SIZE / 2
    for ring in range(1, 6):
        r = ring * 1000.0 / MM_PER_PX
        draw.ellipse((c - r, c - r, c + r, c + r), outline=(210, 210, 200))
    if points:
        pts = np.asarray(points, dtype=float)
        cols = c - pts[:, 1] / MM_PER_PX  # platform y (left) -> image left
        rows = c - pts[:, 0] / MM_PER_PX  # platform x (ahead) -> image up
        keep = (cols >= 0) & (cols < SIZE) & (rows >= 0) & (rows < SIZE)
        for col, row in zip(cols[keep], rows[keep], strict=True):
            draw.rectangle((col - 1, row - 1, col + 1, row + 1), fill=(200, 30, 30))
    half = 300.0 / MM_PER_PX
    nose = (c, c - 1.6 * half)
    draw.polygon([nose, (c - half, c + half), (c + half, c + half)], outline=(20, 60, 160), width=2)
    out = io.BytesIO()
    img.save(out, format="JPEG", quality=85)
    return out.getvalue()


def write_grab(
    folder: Path,
    filename: str,
    scan: bool,
    image: bool,
    points: Sequence[Point],
    pose: tuple[float, float, float],
    now: float,
) -> list[str]:
    """Write the requested files into ``folder``; returns their paths. OSError when the disk refuses."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    if scan:
        path = folder / f"{filename}.dat"
        path.write_text(scan_text(points, pose, now), encoding="ascii")
        written.append(str(path))
    if image:
        path = folder / f"{filename}.jpg"
        path.write_bytes(render_jpeg(points))
        written.append(str(path))
    return written
