"""Headless pictures of the scene (PyBullet's TinyRenderer, saved as PNG with Pillow)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import MissingDependency

__all__ = ["render", "save_png"]


def render(
    client: Any,
    *,
    width: int = 960,
    height: int = 640,
    target: Sequence[float] = (0.9, 0.0, 0.25),
    distance: float = 2.3,
    yaw_deg: float = -30.0,
    pitch_deg: float = -30.0,
    fov_deg: float = 45.0,
) -> np.ndarray:
    """Render the scene with the TinyRenderer (no display needed).

    Args:
        client: a pybullet BulletClient.
        width, height: image size [px].
        target: the point the camera looks at [m, W].
        distance: camera distance from the target [m].
        yaw_deg, pitch_deg: camera yaw and pitch about the target [deg].
        fov_deg: vertical field of view [deg].

    Returns:
        RGB image, shape (height, width, 3), uint8.
    """
    view = client.computeViewMatrixFromYawPitchRoll(
        cameraTargetPosition=list(target),
        distance=distance,
        yaw=yaw_deg,
        pitch=pitch_deg,
        roll=0.0,
        upAxisIndex=2,
    )
    proj = client.computeProjectionMatrixFOV(
        fov=fov_deg, aspect=width / height, nearVal=0.05, farVal=20.0
    )
    _, _, rgba, _, _ = client.getCameraImage(
        width,
        height,
        viewMatrix=view,
        projectionMatrix=proj,
        renderer=client.ER_TINY_RENDERER,
        lightDirection=[1.0, -1.5, 3.0],
        shadow=1,
    )
    img = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
    return img[:, :, :3].copy()


def save_png(image: np.ndarray, path: str | Path) -> Path:
    """Write an RGB image as PNG.

    Raises:
        MissingDependency: Pillow is not installed.
    """
    try:
        from PIL import Image
    except ImportError:
        raise MissingDependency("snapshots need Pillow: pip install pillow") from None
    p = Path(path)
    Image.fromarray(image).save(p)
    return p
