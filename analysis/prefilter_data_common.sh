# shellcheck shell=bash
# prefilter_data_common.sh -- sourced (not run) by the scripts that write the committed prefilter CSVs
# (prefilter_eval_data.sh, prefilter_scenes_lights.sh, prefilter_figures_data.sh): the provenance date and
# the check that a reused `mfkit prefilter` output is the run the provenance line names.

# pf_stamp: the provenance line's date, UTC: SOURCE_DATE_EPOCH (seconds since 1970) when it is set (the
# reproducible-builds convention; with a committed file's date the scripts rewrite it byte for byte),
# else now.
pf_stamp() {
    if [ -n "${SOURCE_DATE_EPOCH:-}" ]; then
        case "$SOURCE_DATE_EPOCH" in
            *[!0-9]*) echo "SOURCE_DATE_EPOCH=$SOURCE_DATE_EPOCH: not a whole number of seconds" >&2; return 2 ;;
        esac
        date -u -d "@$SOURCE_DATE_EPOCH" +%Y-%m-%dT%H:%M:%SZ
    else
        date -u +%Y-%m-%dT%H:%M:%SZ
    fi
}

# pf_check PF MAP N_THETA N_PHI: PF/prefilter.json must be `mfkit prefilter MAP --base ggx --views
# N_THETAxN_PHI` with the other fit options at their defaults (alpha 0.1, views up to 0.999 pi/2, 4096
# directions, 100 iterations, seed 1); else one line naming PF and what differs, status 2.
pf_check() {
    /usr/bin/python3 - "$@" <<'PYEOF'
import json, math, sys
pf, want_map, nt, np_ = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
try:
    with open(pf + "/prefilter.json") as f:
        m = json.load(f)
except (OSError, ValueError) as e:
    sys.stderr.write("%s/prefilter.json: unreadable (%s)\n" % (pf, e))
    sys.exit(2)
fit, base, axes = m.get("fit", {}), m.get("base_brdf", {}), m.get("axes", {})
theta, phi = axes.get("theta", []), axes.get("phi", [])
checks = [("map", m.get("map"), want_map), ("base", base.get("model"), "ggx"), ("alpha", base.get("alpha"), 0.1),
          ("elevations", len(theta), nt), ("azimuths", len(phi), np_),
          ("largest elevation", theta[-1] if theta else None, 0.999 * math.pi / 2),
          ("samples", fit.get("samples"), 4096), ("max_iterations", fit.get("max_iterations"), 100),
          ("seed", fit.get("seed"), 1)]
for what, got, want in checks:
    if got != want:
        sys.stderr.write("%s: not the recorded prefilter run: %s is %r, expected %r\n" % (pf, what, got, want))
        sys.exit(2)
PYEOF
}
