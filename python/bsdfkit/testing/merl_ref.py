"""Independent numpy reference for MERL tables (Matusik et al. 2003): the bin indices of a
direction pair as MERL's BRDFRead.cpp computes them (std_coords_to_half_diff_coords with
in = wi, out = wo; written with numpy from the reference code's rotations, not from bsdfkit's C++),
and the trilinear weights of bsdfkit's ``interpolation="linear"`` between bin centres."""
from __future__ import annotations

import numpy as np

__all__ = ["index_ref", "linear_corners"]


def index_ref(wo, wi):
    """MERL BRDFRead.cpp: std_coords_to_half_diff_coords(in = wi, out = wo) and the bin indices
    (theta_half_index, theta_diff_index, phi_diff_index), written independently with numpy."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    th = np.arccos(np.clip(h[..., 2], -1, 1))
    ph = np.arctan2(h[..., 1], h[..., 0])

    def rot(v, axis, ang):   # Rodrigues, as rotate_vector
        c, s = np.cos(ang)[..., None], np.sin(ang)[..., None]
        return v * c + axis * np.sum(v * axis, -1, keepdims=True) * (1 - c) + np.cross(axis, v) * s

    n = np.broadcast_to([0.0, 0.0, 1.0], wi.shape)
    b = np.broadcast_to([0.0, 1.0, 0.0], wi.shape)
    d = rot(rot(wi, n, -ph), b, -th)
    td = np.arccos(np.clip(d[..., 2], -1, 1))
    pd = np.arctan2(d[..., 1], d[..., 0])
    pd = np.where(pd < 0, pd + np.pi, pd)
    ih = np.where(th <= 0, 0, np.clip((np.sqrt(np.maximum(th, 0) / (np.pi / 2)) * 90).astype(int), 0, 89))
    idd = np.clip((td / (np.pi / 2) * 90).astype(int), 0, 89)
    ip = np.clip((pd / np.pi * 180).astype(int), 0, 179)
    return ih, idd, ip, th, td, pd


def linear_corners(th, td, pd):
    """The 8 (theta_h, theta_d, phi_d) bins and weights of the trilinear lookup between bin centres
    (clamped in theta_h, theta_d; periodic in phi_d), from index_ref's angles: a list of
    ((ih, id, ip), weight) with arrays of the pairs' shape."""
    xh = np.clip(np.sqrt(th / (np.pi / 2)) * 90 - 0.5, 0, 89)
    xd = np.clip(td / (np.pi / 2) * 90 - 0.5, 0, 89)
    xp = pd / np.pi * 180 - 0.5
    h0, d0 = np.minimum(xh.astype(int), 88), np.minimum(xd.astype(int), 88)
    p0 = np.floor(xp).astype(int)
    wh, wd, wp = xh - h0, xd - d0, xp - p0
    out = []
    for a, wa in ((h0, 1 - wh), (h0 + 1, wh)):
        for b, wb in ((d0, 1 - wd), (d0 + 1, wd)):
            for p, wpp in ((p0 % 180, 1 - wp), ((p0 + 1) % 180, wp)):
                out.append(((a, b, p), wa * wb * wpp))
    return out
