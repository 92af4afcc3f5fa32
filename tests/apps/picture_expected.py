#!/usr/bin/python3
"""What `dfbwall show` must put in a window, computed apart from dfbwall: the picture decoded by
Pillow, put over the background, fitted into the window keeping its aspect and scaled as
docs/service.md ("Pictures beside renders") defines it, in numpy integer arithmetic.

  picture_expected.py make DIR         test pictures: plot.png (RGBA, 97x61, partly transparent)
                                       and seq-0001.jpg .. seq-0003.jpg (60x80, 4:2:0 as
                                       photos are)
  picture_expected.py fit PICTURE W H nearest|bilinear #rrggbb OUT.png
"""
import sys

import numpy as np
from PIL import Image


def make(folder):
    rng = np.random.default_rng(37)
    h, w = 61, 97
    y, x = np.mgrid[0:h, 0:w]
    plot = np.zeros((h, w, 4), np.uint8)
    plot[..., 0] = (x * 255 // (w - 1)).astype(np.uint8)
    plot[..., 1] = (y * 255 // (h - 1)).astype(np.uint8)
    plot[..., 2] = rng.integers(0, 256, (h, w), dtype=np.uint8)
    plot[..., 3] = np.where((x - 48) ** 2 + (y - 30) ** 2 < 20 ** 2, 255, (x * 4) % 256).astype(np.uint8)
    Image.fromarray(plot, "RGBA").save(f"{folder}/plot.png")
    for k in range(1, 4):
        frame = np.zeros((80, 60, 3), np.uint8)
        frame[..., k - 1] = 200
        frame[10 * k:10 * k + 20, 5:55] = (255, 255, 255)
        Image.fromarray(frame, "RGB").save(f"{folder}/seq-{k:04d}.jpg", quality=90)


def fit(pw, ph, ww, wh):
    if pw * wh <= ph * ww:
        h, w = wh, min(max((2 * pw * wh + ph) // (2 * ph), 1), ww)
    else:
        w, h = ww, min(max((2 * ph * ww + pw) // (2 * pw), 1), wh)
    return (ww - w) // 2, (wh - h) // 2, w, h


def taps(scaled, source):
    """Bilinear: first and second source index and the second's weight over 2 * scaled."""
    u = np.arange(scaled, dtype=np.int64)
    n = (2 * u + 1) * source - scaled
    first = np.where(n > 0, n // (2 * scaled), 0)
    weight = np.where(n > 0, n % (2 * scaled), 0)
    clamp = first >= source - 1
    first = np.where(clamp, source - 1, first)
    weight = np.where(clamp, 0, weight)
    return first, np.minimum(first + 1, source - 1), weight


def expected(picture, ww, wh, filt, background):
    src = np.asarray(Image.open(picture).convert("RGBA")).astype(np.int64)
    ph, pw = src.shape[:2]
    bg = np.array([int(background[i:i + 2], 16) for i in (1, 3, 5)] + [255], np.int64)
    a = src[..., 3:4]
    flat = np.concatenate([(src[..., :3] * a + bg[:3] * (255 - a) + 127) // 255,
                           np.full((ph, pw, 1), 255, np.int64)], axis=2)
    x0, y0, w, h = fit(pw, ph, ww, wh)
    out = np.broadcast_to(bg, (wh, ww, 4)).copy()
    if filt == "nearest":
        sx = (2 * np.arange(w) + 1) * pw // (2 * w)
        sy = (2 * np.arange(h) + 1) * ph // (2 * h)
        part = flat[sy][:, sx]
    else:
        fx, sx, wx = taps(w, pw)
        fy, sy, wy = taps(h, ph)
        dx, dy = 2 * w, 2 * h
        wx = wx[None, :, None]
        wy = wy[:, None, None]
        top = flat[fy][:, fx] * (dx - wx) + flat[fy][:, sx] * wx
        bottom = flat[sy][:, fx] * (dx - wx) + flat[sy][:, sx] * wx
        part = (top * (dy - wy) + bottom * wy + dx * dy // 2) // (dx * dy)
    out[y0:y0 + h, x0:x0 + w] = part
    return out.astype(np.uint8)


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2])
    else:
        _, _, picture, ww, wh, filt, background, target = sys.argv
        Image.fromarray(expected(picture, int(ww), int(wh), filt, background), "RGBA").save(target)
