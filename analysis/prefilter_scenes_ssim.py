#!/usr/bin/python3
"""prefilter_scenes_ssim.py DIR [--csv FILE] -- a perceptual image metric for the scene renders of
analysis/render_prefilter_scenes: SSIM [Wang, Bovik, Sheikh, Simoncelli 2004, "Image Quality Assessment:
From Error Visibility to Structural Similarity", IEEE TIP 13(4)] of each method's PNG image against the
truth's, by Debian's python3-skimage (skimage.metrics.structural_similarity with the paper's settings:
11 x 11 Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03, population covariances, data range 1).

The PNG images are the display images (radiance / the truth's largest value of that scene and distance,
gamma 1/2.2, 8 bits), the same normalisation for every method, which is what a perceptual metric should
see.  The thesis used FLIP [Andersson et al. 2020], which Debian does not package.  Reported per scene,
distance and method: `ssim`, the mean of the SSIM map over the pixels where the truth or the method is
non-zero (the plane: the background is 0 in every image), and `ssim_image`, the mean over the whole
image.  1 is identical; lower is worse.

Writes DIR/prefilter_scenes_ssim.csv (or --csv FILE); its first line is the provenance header, with the
mfkit version read from DIR/prefilter_scenes.csv.
"""
import csv
import datetime
import os
import re
import sys

try:
    import numpy as np
    from matplotlib.image import imread
    from skimage.metrics import structural_similarity
except ImportError as exc:  # the README's install line provides them
    sys.stderr.write("prefilter_scenes_ssim.py: needs python3-numpy, python3-matplotlib and python3-skimage: %s\n"
                     % exc)
    sys.exit(3)

METHODS = ("truth_mc", "mfkit", "naive", "toksvig", "leadr", "mfkit_taps")


def main(argv):
    args = argv[1:]
    out = None
    if len(args) == 3 and args[1] == "--csv":
        out = args[2]
        args = args[:1]
    if len(args) != 1 or args[0].startswith("-"):
        sys.stderr.write("usage: prefilter_scenes_ssim.py DIR [--csv FILE]\n")
        return 2
    d = args[0]
    if not os.path.isdir(d):
        sys.stderr.write("prefilter_scenes_ssim.py: %s: not a directory\n" % d)
        return 3
    out = out or os.path.join(d, "prefilter_scenes_ssim.csv")
    version = "unknown"
    try:
        with open(os.path.join(d, "prefilter_scenes.csv")) as f:
            m = re.search(r"mfkit=([^,]+),", f.readline())
            version = m.group(1) if m else version
    except OSError:
        pass
    pat = re.compile(r"^(normal|grazing)_d(.+)_truth\.png$")
    keys = sorted(((m.group(1), m.group(2)) for m in map(pat.match, os.listdir(d)) if m),
                  key=lambda k: (k[0] != "normal", float(k[1])))
    if not keys:
        sys.stderr.write("prefilter_scenes_ssim.py: %s: no <scene>_d<d>_truth.png (run render_prefilter_scenes "
                         "with --images 1)\n" % d)
        return 3
    rows = []
    for scene, dist in keys:
        base = os.path.join(d, "%s_d%s_" % (scene, dist))
        truth = imread(base + "truth.png").astype(np.float64)
        for method in METHODS:
            path = base + method + ".png"
            if not os.path.exists(path):
                continue
            img = imread(path).astype(np.float64)
            if img.shape != truth.shape or img.ndim != 2:
                sys.stderr.write("prefilter_scenes_ssim.py: %s: not a grey image of the truth's size\n" % path)
                return 3
            whole, smap = structural_similarity(truth, img, data_range=1.0, gaussian_weights=True, sigma=1.5,
                                                use_sample_covariance=False, full=True)
            mask = (truth > 0) | (img > 0)
            plane = float(np.mean(smap[mask])) if mask.any() else float("nan")
            rows.append((scene, dist, method, int(mask.sum()), plane, float(whole)))
    tmp = out + ".tmp"
    with open(tmp, "w", newline="") as f:
        date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        f.write("# command=prefilter_scenes_ssim.py %s, mfkit=%s, seed=none, date=%s\n"
                % (os.path.basename(os.path.normpath(d)), version, date))
        w = csv.writer(f, lineterminator="\n")
        w.writerow(("scene", "distance", "method", "pixels", "ssim", "ssim_image"))
        for r in rows:
            w.writerow((r[0], r[1], r[2], r[3], "%.6f" % r[4], "%.6f" % r[5]))
    os.replace(tmp, out)
    print("wrote %s" % out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
