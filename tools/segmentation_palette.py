#!/usr/bin/env python3
"""Prints the segmentation palette of render/renderer.cc (kSegmentationPalette).

Greedy farthest-point selection in CIEDE2000 over the sRGB grid of 16 levels per channel
(0, 17, ..., 255): black, the background, is placed first, colours darker than L* 35 are left
out, and each next colour is the candidate farthest from all placed ones (ties: the first in
grid order). Every prefix of the list is therefore spread as far as this greedy choice can: the
first 36 colours (every object of a Fetch model) lie at least 15.9 apart, all 48 at least 14.1.
Pure Python, no dependencies; about 10 s.
"""
import math

N, STEP, MIN_LIGHTNESS = 48, 17, 35.0


def linear(c):
    c /= 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def lab(rgb):
    r, g, b = (linear(c) for c in rgb)
    x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047
    y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b
    z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883
    f = lambda t: t ** (1 / 3) if t > 216 / 24389 else (24389 / 27 * t + 16) / 116
    fx, fy, fz = f(x), f(y), f(z)
    return (116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz))


def ciede2000(lab1, lab2):
    L1, a1, b1 = lab1
    L2, a2, b2 = lab2
    cbar = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2
    g = 0.5 * (1 - math.sqrt(cbar**7 / (cbar**7 + 25**7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1p, c2p = math.hypot(a1p, b1), math.hypot(a2p, b2)
    h1p = math.degrees(math.atan2(b1, a1p)) % 360 if c1p else 0
    h2p = math.degrees(math.atan2(b2, a2p)) % 360 if c2p else 0
    dl, dc = L2 - L1, c2p - c1p
    dh = 0
    if c1p * c2p:
        dh = h2p - h1p
        dh = dh - 360 if dh > 180 else dh + 360 if dh < -180 else dh
    dhh = 2 * math.sqrt(c1p * c2p) * math.sin(math.radians(dh / 2))
    lbar, cbarp = (L1 + L2) / 2, (c1p + c2p) / 2
    if c1p * c2p == 0:
        hbar = h1p + h2p
    elif abs(h1p - h2p) <= 180:
        hbar = (h1p + h2p) / 2
    else:
        hbar = (h1p + h2p + 360) / 2 if h1p + h2p < 360 else (h1p + h2p - 360) / 2
    t = (1 - 0.17 * math.cos(math.radians(hbar - 30)) + 0.24 * math.cos(math.radians(2 * hbar))
         + 0.32 * math.cos(math.radians(3 * hbar + 6)) - 0.20 * math.cos(math.radians(4 * hbar - 63)))
    dtheta = 30 * math.exp(-(((hbar - 275) / 25) ** 2))
    rc = 2 * math.sqrt(cbarp**7 / (cbarp**7 + 25**7))
    sl = 1 + 0.015 * (lbar - 50) ** 2 / math.sqrt(20 + (lbar - 50) ** 2)
    sc, sh = 1 + 0.045 * cbarp, 1 + 0.015 * cbarp * t
    rt = -math.sin(math.radians(2 * dtheta)) * rc
    return math.sqrt((dl / sl) ** 2 + (dc / sc) ** 2 + (dhh / sh) ** 2 + rt * (dc / sc) * (dhh / sh))


def main():
    levels = list(range(0, 256, STEP))
    grid = [(r, g, b) for r in levels for g in levels for b in levels]
    labs = [lab(c) for c in grid]
    black = lab((0, 0, 0))
    nearest = [ciede2000(l, black) if l[0] >= MIN_LIGHTNESS else -1.0 for l in labs]
    chosen = []
    for _ in range(N):
        i = max(range(len(grid)), key=lambda j: (nearest[j], -j))
        chosen.append(grid[i])
        nearest = [min(d, ciede2000(labs[j], labs[i])) for j, d in enumerate(nearest)]
    print(", ".join("0x%02X%02X%02X" % c for c in chosen))


if __name__ == "__main__":
    main()
