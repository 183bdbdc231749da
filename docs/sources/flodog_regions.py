"""Where RHS2007's authors put region.hi, in stimupy's pictures: how the benchmark's RHS2007
entries of ``SOURCES`` (python/shadelab/_benchmark_data.py) were derived.

The test patterns of github srhande/flodog-models at commit
7d792958a1c377faf8a8ab82d42150011fc55806 (``testpatterns/make_*.m``, with
``functions/model_pad_patch.m`` and ``functions/label_regions.m``), ported line by line from
MATLAB to NumPy (1-based inclusive ranges become slices; the grey regions are numbered in
raster order with 4-neighbour connectivity, as ``grow_region.m`` grows them). For each
stimulus it prints the picture frame (same, or mirrored left-right) in which the source's
picture and stimupy 1.2.0's differ on the fewest pixels, that fraction, the centroid of
``region.hi`` in that frame (degrees from the picture's centre, x right, y up: the recorded
``at``) and how many of its pixels fall on stimupy's target 1 and 2, and the mean luminance
just around region.hi and around each stimupy target (3 pixels wide). Where no frame matches
the pixels closely (checkerboard_016: its 5-pixel checks are out of phase in both frames,
8.8 % and 10.7 % of the pixels differ), the surround decides: region.hi lies among white
checks, as stimupy's target 2 does, so the recorded position is the same frame's.

Run with a Python that has stimupy 1.2.0 and SciPy: ``python3 docs/sources/flodog_regions.py``.
A record of how the table was made, not part of shadelab: the test suite checks the recorded
positions against stimupy's masks without it.
"""

import warnings

import numpy as np
from scipy import ndimage


def R(a, b):  # MATLAB a:b (1-based inclusive) -> python slice
    return slice(int(a) - 1, int(b))


def pad(model, h=1024, w=1024):
    """model_pad_patch.m: centre the picture on a 0.5 grey field."""
    y, x = model.shape
    h = max(h, y)
    w = max(w, x)
    p = np.full((h, w), 0.5)
    p[R(h / 2 - y / 2 + 1, h / 2 + y / 2), R(w / 2 - x / 2 + 1, w / 2 + x / 2)] = model
    return p


def label(img, value=0.5):
    """label_regions.m: the regions of grey ``value``, numbered in raster order."""
    lab, _ = ndimage.label(img == value)
    return lab.astype(float)


def whites_param(width, height, patchy, inlay, scale, leftmost):
    patchy = patchy / 2
    m = np.zeros((height * scale, width * scale))
    for i in range(1, width * scale + 1):
        m[:, i - 1] = ((i - 1) // scale) % 2
    if leftmost:
        m = 1 - m
    rows = R((height / 2) * scale - patchy * scale, (height / 2) * scale + patchy * scale)
    m[rows, R(1 + (inlay - 1) * scale, inlay * scale)] = 0.5
    i2 = width - inlay
    m[rows, R(1 + i2 * scale, (i2 + 1) * scale)] = 0.5
    return m


def anderson_howe(lg, rg):
    b = np.full((768, 1024), 0.5)
    b[R(144, 144 + 480), R(256, 256 + 512)] = 1
    ph = 96
    for n in range(8):
        for k in (0, 2, 4):
            b[R(144 + ph * k, 144 + ph * (k + 1)), R(256 + 64 * n, 256 + 64 * n + 32)] = 0
    for n in range(16):
        b[R(144 + ph, 144 + ph * 2), R(256 + 32 * n, 256 + 32 * n + 32)] = 0
    b[R(144, 144 + ph * 5), R(256 + 160, 256 + 192)] = 1
    b[R(144, 144 + ph * 5), R(256 + 320, 256 + 352)] = 0
    b[R(144 + ph * lg, 144 + ph * (lg + 1)), R(256 + 160, 256 + 192)] = 0.5
    b[R(144 + ph * rg, 144 + ph * (rg + 1)), R(256 + 320, 256 + 352)] = 0.5
    return b


def grating():
    t = np.linspace(0, 1, 512)  # [0:(1/511):1]
    m = np.tile(0.5 + np.sin(4 * 2 * np.pi * t) / 2, (384, 1))
    m[R(176, 176 + 32), :] = 0.5
    return m


def sbc(deg):
    b = np.ones((384, 480))
    y, x = b.shape
    p = deg * 32 / 2
    b[R(y / 2 - p, y / 2 + p), R(x / 2 - p, x / 2 + p)] = 0.5
    return np.hstack([b, 1 - b])


def todorovic(kind):
    b = np.ones((384, 492))
    L = {"equal": 240, "in-large": 170, "in-small": 96, "out": 280}[kind]
    if kind == "out":
        b[R(192 - L / 2, 192 - L / 2 + L), R(223, 269)] = 0.5
        b[R(169, 215), R(246 - L / 2, 246 - L / 2 + L)] = 0.5
    else:
        b[R(192 - L / 2, 192 - L / 2 + L), R(222, 270)] = 0.5
        b[R(168, 216), R(246 - L / 2, 246 - L / 2 + L)] = 0.5
    for rr, cc in [((72, 168), (126, 222)), ((216, 312), (126, 222)),
                   ((72, 168), (270, 366)), ((216, 312), (270, 366))]:
        b[R(*rr), R(*cc)] = 0
    return np.hstack([b, 1 - b])


def check(m, n, sq, tm, tn, sm, sn):
    """make_check_parametric.m."""
    mc, nc = m // sq, n // sq
    col = np.full((m, sq), 0.5)
    this = 0
    for i in range(1, mc + 1):
        col[(i - 1) * sq:i * sq, :] = this
        this = 1 - this
    cols = []
    c = col
    for _ in range(nc):
        cols.append(c)
        c = 1 - c
    board = np.hstack(cols)
    test_m = int(np.floor(tm / sq) * sq)
    test_n = int(np.floor(tn / sq) * sq)
    left = board[test_m - 1, test_n - 1]
    if left == 0:
        test_n += sq
    board[test_m:test_m + sq, test_n:test_n + sq] = 0.5
    test_m = int(np.floor((tm + sm) / sq) * sq)
    test_n = int(np.floor((tn + sn) / sq) * sq)
    right = board[test_m - 1, test_n - 1]
    if left == right:
        test_n -= sq
    board[test_m:test_m + sq, test_n:test_n + sq] = 0.5
    return board


def mondrian():
    b = np.full((1024, 1024), 0.5)

    def sqr(x, y, v):
        s = np.zeros((1024, 1024))
        s[R(y, y + 64), R(x, x + 64)] = v - 0.5
        return s

    def para(kind, x, y, v):
        p = np.zeros((1024, 1024))
        inc = 0
        for n in range(32):
            for k in range(2):
                if kind == 1:
                    p[y + inc + k - 1, R(x - n, x + 64 - n)] = v - 0.5
                else:
                    p[y + inc + k - 1, R(x + n, x + 64 + n)] = v - 0.5
            inc += 2
        return p

    X = Y = 352
    cx = 0
    cy = 65
    for n in range(5):
        v = 0.76 if n % 2 == 0 else 0.48
        b = b + sqr(X + cx, Y, v)
        v = 0.5 if n == 2 else (1.0 if n % 2 == 0 else 0.81)
        b = b + para(1, X + cx, Y + cy, v)
        v = 0.76 if n % 2 == 0 else 0.48
        b = b + sqr(X + cx - 31, Y + cy * 2 - 1, v)
        v = 0.5 if n == 2 else (0.53 if n % 2 == 0 else 0.0)
        b = b + para(2, X + cx - 31, Y + cy * 3 - 1, v)
        v = 0.76 if n % 2 == 0 else 0.48
        b = b + sqr(X + cx, Y + cy * 4 - 2, v)
        cx += 65
    return b


def benary():
    b = np.ones((1024, 1024))
    b[R(1, 310), :] = 0.5
    b[R(714, 1024), :] = 0.5
    b[R(310, 714), R(1, 20)] = 0.5
    b[R(310, 714), R(1024 - 20, 1024)] = 0.5
    b[R(310, 714), R(450, 574)] = 0
    b[R(450, 574), R(140, 884)] = 0
    for n in range(69):
        b[R(380 + n, 380 + n + 1), R(575, 575 + n)] = 0.5
    for n in range(49):
        b[R(450 + n, 450 + n + 1), R(351 + n, 449 - n)] = 0.5
    return b


def tb_base(first_tri_extra):
    b = np.ones((1024, 1024))
    b[R(1, 310), :] = 0.5
    b[R(714, 1024), :] = 0.5
    b[R(311, 512), R(1, 100)] = 0
    b[R(512, 714), R(1, 924)] = 0
    b[R(310, 714), R(1, 20)] = 0.5
    b[R(310, 714), R(1024 - 20, 1024)] = 0.5
    for n in range(69):
        b[R(442 + n, 442 + n + 1), R(101, 101 + n + first_tri_extra)] = 0.5
    for n in range(49):
        b[R(512 + n, 512 + n + 1), R(333 + n, 432 - n)] = 0.5
    for n in range(49):
        b[R(462 + n, 462 + n + 1), R(642 - n, 642 + n)] = 0.5
    for n in range(69):
        b[R(512 + n, 512 + n + 1), R(854 + n, 924)] = 0.5
    return b


def tb12():
    img = pad(tb_base(1))
    lab = label(img)
    for n in range(35):
        lab[R(511 - n - 1, 511 - n), R(101 + n, 101 + n + 1)] = 2.5
    lab[lab == 2] = 0
    lab[lab == 2.5] = 2
    for n in range(49):
        lab[R(512 + n, 512 + n + 1), R(382, 382)] = 3.5
    lab[lab == 4] = 0
    lab[lab == 3.5] = 4
    return img, lab, 4, 2


def tb34():
    img = pad(tb_base(0))
    lab = label(img)
    for n in range(49):
        lab[R(462 + n, 462 + n + 1), R(642, 642)] = 4.5
    lab[lab == 3] = 0
    lab[lab == 4.5] = 3
    for n in range(35):
        lab[R(512 + n, 512 + n + 1), R(924 - n - 1, 924 - n)] = 2.5
    lab[lab == 5] = 0
    lab[lab == 2.5] = 5
    return img, lab, 5, 3


def std(model, hi, lo, fix=None):
    img = pad(model)
    lab = label(img)
    if fix:
        fix(lab)
    return img, lab, hi, lo


def gi_fix(lab):
    lab[R(1, 318), R(1, 1023)] = 2
    lab[R(499, 525), R(455, 505)] = 3
    lab[R(499, 525), R(520, 570)] = 4


def benary_fix(lab):
    lab[lab > 3] = 1


# stimupy name: (make_*.m, the picture with its labels, region.hi and region.lo)
SOURCES = {
    "WE_thick": ("make_bm_whites_thick.m", lambda: std(whites_param(8, 6, 2, 3, 64, 0), 2, 3)),
    "WE_thin_wide": ("make_bm_whites_thin_wide.m", lambda: std(whites_param(16, 12, 2, 4, 32, 1), 2, 3)),
    "WE_anderson": ("make_whites_andersen.m", lambda: std(anderson_howe(1.5, 2.5), 3, 2)),
    "WE_howe": ("make_whites_howe.m", lambda: std(anderson_howe(1, 3), 3, 2)),
    "grating_induction": ("make_small_grating_induction.m", lambda: std(grating(), 3, 4, gi_fix)),
    "sbc_large": ("make_sbc_large.m", lambda: std(sbc(3), 3, 2)),
    "sbc_small": ("make_sbc_small.m", lambda: std(sbc(1), 3, 2)),
    "todorovic_equal": ("make_todorovic.m", lambda: std(todorovic("equal"), 2, 3)),
    "todorovic_in_large": ("make_todorovic.m", lambda: std(todorovic("in-large"), 2, 3)),
    "todorovic_in_small": ("make_todorovic.m", lambda: std(todorovic("in-small"), 2, 3)),
    "todorovic_out": ("make_todorovic.m", lambda: std(todorovic("out"), 2, 3)),
    "checkerboard_016": ("make_check_5.m", lambda: std(check(200, 768, 5, 100, 384 - 175, 0, 350), 3, 2)),
    "checkerboard_094": ("make_check_30.m", lambda: std(check(210, 768, 30, 100, 384 - 180, 0, 360), 2, 3)),
    "checkerboard_21": ("make_check_67.m", lambda: std(check(201, 701, 67, 100.5, 134, 0, 335), 2, 3)),
    "corrugated_mondrian": ("make_mondrian_f.m", lambda: std(mondrian(), 3, 2)),
    "benary_cross": ("make_benary_cross.m", lambda: std(benary(), 3, 2, benary_fix)),
    "todorovic_benary1_2": ("make_todorovic_benary_cross_1_2_diag.m", tb12),
    "todorovic_benary3_4": ("make_todorovic_benary_cross_3_4_diag.m", tb34),
}


def centroid(region, shape, ppd=32):
    """The centroid of the pixels of ``region`` in degrees from the centre (x right, y up)."""
    r, c = np.nonzero(region)
    h, w = shape
    return (c.mean() + 0.5 - w / 2) / ppd, (h / 2 - (r.mean() + 0.5)) / ppd


FRAMES = {"same": lambda a: a, "mirrored": lambda a: a[:, ::-1]}


def ring(img, inside, width=3):
    """The mean of ``img`` over the pixels within ``width`` of ``inside``, outside it."""
    around = ndimage.binary_dilation(inside, iterations=width) & ~inside
    return float(img[around].mean())


def main():
    from stimupy.papers import RHS2007

    for name, (make, build) in SOURCES.items():
        img, lab, hi, _ = build()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = getattr(RHS2007, name)()
        si = np.asarray(s["img"], float)
        sm = np.asarray(s["target_mask"])
        differ = {k: float(np.mean(np.abs(f(img) - si) > 1e-6)) for k, f in FRAMES.items()}
        frame = min(differ, key=differ.get)
        region = FRAMES[frame](lab == hi)
        x, y = centroid(region, img.shape)
        on = [int((region & (sm == t)).sum()) for t in (1, 2)]
        rings = [ring(FRAMES[frame](img), region)] + [ring(si, sm == t) for t in (1, 2)]
        print(
            f"{name:20s} {make:40s} region.hi={hi} frame={frame} differ={differ[frame]:.3f} "
            f"(same {differ['same']:.3f}) at=({x:+.2f}, {y:+.2f}) pixels on target 1, 2: "
            f"{on[0]}, {on[1]}; around region.hi {rings[0]:.2f}, target 1 {rings[1]:.2f}, "
            f"target 2 {rings[2]:.2f}"
        )


if __name__ == "__main__":
    main()
