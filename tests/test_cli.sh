#!/usr/bin/env bash
# test_cli.sh MFKIT -- the command line end to end: every eval function, and every kind of bad
# input gives one line on stderr, exit code 2 and nothing on stdout.
mfkit="$1"
. "$(dirname "$0")/cli_test_lib.sh"

# expect_error DESCRIPTION STDIN ARGS... : exit 2, empty stdout, one stderr line naming the problem
expect_error() { local desc="$1" input="$2" pattern="$3"; shift 3; expect_error_in "$desc" "$input" 2 "$pattern" "$@"; }

# --- every function, one row, with the exact output header ---------------------------------
run() { printf '%s\n%s\n' "$2" "$3" | "$mfkit" eval $1 2>"$tmp/err"; }
out=$(run "ndf --ndf ggx" "alpha_x,alpha_y,m_x,m_y,m_z" "0.5,0.5,0,0,1")
ok '[ "$(echo "$out" | head -1)" = "alpha_x,alpha_y,m_x,m_y,m_z,D" ]' "ndf header"
# D(z) = 1/(pi alpha^2) = 1.2732395447351628 for alpha 0.5
ok '[ "$(echo "$out" | tail -1)" = "0.5,0.5,0,0,1,1.2732395447351628" ]' "ndf value: $out"
out=$(run "slope-pdf --ndf beckmann" "alpha_x,alpha_y,slope_x,slope_y" "1,1,0,0")
ok '[ "$(echo "$out" | tail -1)" = "1,1,0,0,0.31830988618379069" ]' "slope-pdf value: $out"
out=$(run "lambda --ndf beckmann" "alpha_x,alpha_y,w_x,w_y,w_z" "0.3,0.3,0.6,0,0.8")
ok '[ "$(echo "$out" | head -1)" = "alpha_x,alpha_y,w_x,w_y,w_z,Lambda,Lambda_approx" ]' "lambda beckmann header"
out=$(run "lambda --ndf ggx" "alpha_x,alpha_y,w_x,w_y,w_z" "0.3,0.3,0.6,0,-0.8")
ok '[ "$(echo "$out" | tail -1)" = "0.3,0.3,0.6,0,-0.8,inf" ]' "lambda below horizon is inf: $out"
out=$(run "lambda-gaussian" "mean_x,mean_y,var_x,var_y,cov_xy,w_x,w_y,w_z" "0,0.3,2,0.5,-0.9,0.4980973490458729,-0.8627299156628209,0.08715574274765814")
ok 'echo "$out" | tail -1 | grep -q ",1.03105338564"' "lambda-gaussian, the value of docs/math.md correction C-L2: $out"
out=$(run "g2 --ndf ggx" "alpha_x,alpha_y,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z" "0.3,0.3,0,0,1,0,0,1")
ok '[ "$(echo "$out" | tail -1)" = "0.3,0.3,0,0,1,0,0,1,1,1,1,1" ]' "g2 at normal incidence: $out"
out=$(printf 'alpha_x,alpha_y,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z,f0\n0.3,0.3,0,0,1,0,0,1,0.04\n' | "$mfkit" eval brdf --ndf ggx --fresnel schlick)
ok 'echo "$out" | head -1 | grep -q ",f0,f$"' "brdf schlick header: $out"
out=$(run "albedo --ndf ggx" "alpha,cos_theta_o" "0.5,0.5")
ok 'echo "$out" | head -1 | grep -q "alpha,cos_theta_o,albedo,albedo_err"' "albedo header"
# issue 4 and 5 functions: closed forms
out=$(run "ggx-proxy" "alpha,dh" "0.5,0")
ok '[ "$(echo "$out" | tail -1)" = "0.5,0,0.5,0.5,0.5" ]' "ggx-proxy dh=0 is alpha: $out"
out=$(run "beckmann-filter" "alpha_x,alpha_y,cov_xx,cov_xy,cov_yy" "0.2,0.1,0.01,0.002,0.02")
ok 'echo "$out" | tail -1 | grep -q ",0.0300*[0-9]*,0.002,0.0250*[0-9]*$"' "beckmann-filter B + P: $out"
out=$(run "bump-roughness" "var_u,var_v,cov_uv,alpha_u,alpha_v" "0.01,0.01,0,0.1,0.1")
ok '[ "$(echo "$out" | tail -1)" = "0.01,0.01,0,0.1,0.1,0.17320508075688773,0.17320508075688773,1,0" ]' "bump-roughness sqrt(a^2 + 2 var): $out"
out=$(run "sh-irradiance" "L00,L1m1,L10,L11,L2m2,L2m1,L20,L21,L22,n_x,n_y,n_z" "3.5449077018110318,0,0,0,0,0,0,0,0,0,0,1")
ok 'echo "$out" | tail -1 | grep -q ",3.14159265358979"' "sh-irradiance of a constant sky is pi: $out"
out=$(run "ggx-rect" "alpha_x,alpha_y,x0,x1,y0,y1" "0.3,0.3,-1e-9,1e-9,-1e-9,1e-9")
ok 'echo "$out" | tail -1 | grep -q ",3.536776513153"' "ggx-rect of a tiny square is the peak 1/(pi a^2): $out"
out=$(printf 'mean_x,mean_y,var_x,var_y,cov_xy,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z\n0,0,0.02,0.02,0,0,0,1,0.6,0,0.8\n' | "$mfkit" eval leadr --grid 8 --lambda 3 --grid-layout cell-centres)
ok 'echo "$out" | head -1 | grep -q ",specular,diffuse$"' "leadr header: $out"
expect_error "grid on ndf" "" "does not take --grid" eval ndf --ndf ggx --grid 3
expect_error "bad grid" "" "--grid: expected an integer in \[1, 512\], got '0'" eval leadr --grid 0
expect_error "bad lambda" "" "--lambda: expected a finite number > 0, got '-1'" eval leadr --lambda -1
# out-of-domain rows give nan, the other rows are unaffected; extra columns are echoed
out=$(printf 'id,alpha_x,alpha_y,m_x,m_y,m_z\na,-1,0.5,0,0,1\nb,0.5,0.5,0,0,1\nc,nan,0.5,0,0,1\n' | "$mfkit" eval ndf --ndf ggx)
ok '[ "$(echo "$out" | sed -n 2p)" = "a,-1,0.5,0,0,1,nan" ]' "negative alpha -> nan: $out"
ok '[ "$(echo "$out" | sed -n 3p)" = "b,0.5,0.5,0,0,1,1.2732395447351628" ]' "valid row after a bad one"
ok '[ "$(echo "$out" | sed -n 4p)" = "c,nan,0.5,0,0,1,nan" ]' "nan input -> nan"
# CRLF input and spaces are accepted
out=$(printf 'alpha_x, alpha_y ,m_x,m_y,m_z\r\n0.5,0.5,0,0,1\r\n' | "$mfkit" eval ndf --ndf ggx)
ok 'echo "$out" | tail -1 | grep -q "1.2732395447351628"' "CRLF input"
# many rows: bounded memory and time
/usr/bin/env awk 'BEGIN{print "alpha_x,alpha_y,w_x,w_y,w_z"; for(i=0;i<100000;i++) print 0.1+i*1e-6",0.2,0.6,0,0.8"}' >"$tmp/big.csv"
ok '[ "$("$mfkit" eval lambda --ndf ggx <"$tmp/big.csv" | wc -l)" -eq 100001 ]' "100k rows"

# --- errors: one line, exit 2, no stdout -----------------------------------------------------
H="alpha_x,alpha_y,m_x,m_y,m_z"
expect_error "missing column" "alpha_x,alpha_y,m_x,m_y
1,1,0,0
" "missing required column 'm_z'" eval ndf --ndf ggx
expect_error "non-number field" "$H
0.5,0.5,0,0,1
0.5,abc,0,0,1
" "data row 2, column 'alpha_y': 'abc' is not a number" eval ndf --ndf ggx
expect_error "ragged row" "$H
0.5,0.5,0,0
" "line 2: 4 fields, but the header has 5" eval ndf --ndf ggx
expect_error "empty input" "" "empty input" eval ndf --ndf ggx
expect_error "unknown function" "" "unknown function 'nope'" eval nope
expect_error "missing function" "" "missing FUNCTION" eval
expect_error "unknown option" "" "unknown option '--bogus'" eval ndf --ndf ggx --bogus
expect_error "missing value" "" "option --ndf needs a value" eval ndf --ndf
expect_error "bad ndf" "" "mfkit eval: --ndf: expected ggx or beckmann, got 'phong'" eval ndf --ndf phong
expect_error "repeated option" "" "--ndf given twice" eval ndf --ndf ggx --ndf beckmann
expect_error "1e400 option" "" "--lambda: '1e400' is out of the range" eval leadr --lambda 1e400
expect_error "ndf required" "" "--ndf ggx|beckmann is required" eval lambda
expect_error "ndf not taken" "" "does not take --ndf" eval lambda-gaussian --ndf ggx
expect_error "fresnel on ndf" "" "does not take --fresnel" eval ndf --ndf ggx --fresnel schlick
expect_error "bad points" "" "--points: expected a multiple of 8 in \[16, 2048\], got 'nan'" eval albedo --ndf ggx --points nan
expect_error "points not multiple" "" "--points: expected a multiple of 8 in \[16, 2048\], got '100'" eval albedo --ndf ggx --points 100
expect_error "f0 missing" "alpha_x,alpha_y,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z
1,1,0,0,1,0,0,1
" "missing required column 'f0'" eval brdf --ndf ggx --fresnel schlick
expect_error "duplicate header" "m_x,m_x
" "names column 'm_x' twice" eval ndf --ndf ggx
expect_error "output name clash" "$H,D
0.5,0.5,0,0,1,3
" "already has a column named 'D'" eval ndf --ndf ggx
expect_error "unknown command" "" "unknown command 'fitt'" fitt
expect_error "validate bad option" "" "unknown option '--fast'" validate --fast
expect_error "validate missing value" "" "--json-file needs a value" validate --json-file

# --- faults of issue 11: extreme arguments give values, input errors name their cause -----------
# ggx-proxy: a subnormal dh against alpha >= 1 is alpha (t/atan t = 1); dh >= 1e155 follows
# alpha' -> dh/sqrt(pi) (1/sqrt(pi) = 0.56418958354775628...) instead of overflowing to inf
out=$(run "ggx-proxy" "alpha,dh" "1,5e-324")
ok '[ "$(echo "$out" | tail -1)" = "1,5e-324,1,1,1" ]' "ggx-proxy subnormal dh, alpha 1: $out"
out=$(run "ggx-proxy" "alpha,dh" "2,1e-310")
ok '[ "$(echo "$out" | tail -1)" = "2,1e-310,2,2,2" ]' "ggx-proxy subnormal dh, alpha 2: $out"
out=$(run "ggx-proxy" "alpha,dh" "0.5,1e155")
ok 'echo "$out" | tail -1 | grep -q "^0.5,1e155,5.64189583547756[0-9]*e+154,"' "ggx-proxy dh 1e155: $out"
out=$(run "ggx-proxy" "alpha,dh" "1,1e308")
ok 'echo "$out" | tail -1 | grep -q "^1,1e308,5.641895835477562[0-9]*e+307,"' "ggx-proxy dh 1e308: $out"
# ggx-rect with bounds +-1e300: the mean is the mass over the area. [-1e300,1e300] x [-1,1] at
# alpha 0.3 holds the y-marginal mass 1/sqrt(1 + 0.09) = 0.9578262852211514 over the area 4e300,
# 2.3945657130528785e-301; [-1e300,1e300]^2 (area 4e600) underflows to 0.
out=$(printf 'alpha_x,alpha_y,x0,x1,y0,y1
0.3,0.3,-1e300,1e300,-1,1
0.3,0.3,-1e300,1e300,-1e300,1e300
' | "$mfkit" eval ggx-rect)
ok 'echo "$out" | sed -n 2p | grep -q ",2.39456571305287[0-9]*e-301$"' "ggx-rect +-1e300 x +-1: $out"
ok '[ "$(echo "$out" | sed -n 3p)" = "0.3,0.3,-1e300,1e300,-1e300,1e300,0" ]' "ggx-rect +-1e300 square: $out"
expect_error "1e400 out of range" "alpha,dh
1e400,1
" "'1e400' is out of the range of a double" eval ggx-proxy
expect_error "UTF-8 BOM" "$(printf '\xef\xbb\xbfalpha,dh\n1,1\n')" "byte-order mark" eval ggx-proxy
printf 'alpha,dh\n1\0,1\n' >"$tmp/nul.csv"
"$mfkit" eval ggx-proxy <"$tmp/nul.csv" >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 2 ] && [ ! -s "$tmp/out" ] && grep -q "line 2: binary input" "$tmp/err"' "NUL byte named binary: $(cat "$tmp/err")"
head -c 300 /bin/sh >"$tmp/bin.csv"
"$mfkit" eval ggx-proxy <"$tmp/bin.csv" >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 2 ] && [ ! -s "$tmp/out" ] && grep -q "binary input" "$tmp/err"' "an executable named binary: $(cat "$tmp/err")"
# 100k header columns: linear header parsing (was quadratic: 30 s); the row echoes every column
awk 'BEGIN{for(i=0;i<100000;i++) printf "c%d,", i; print "alpha,dh"; for(i=0;i<100000;i++) printf "0,"; print "0.5,0"}' >"$tmp/wide.csv"
ok '[ "$("$mfkit" eval ggx-proxy <"$tmp/wide.csv" | tail -1 | tr , "\n" | tail -3 | tr "\n" " ")" = "0.5 0.5 0.5 " ]' "100k columns"
awk 'BEGIN{for(i=0;i<100000;i++) printf "c%d,", i; print "c77777"}' >"$tmp/dup.csv"
"$mfkit" eval ggx-proxy <"$tmp/dup.csv" >"$tmp/out" 2>"$tmp/err"
ok 'grep -q "names column .c77777. twice" "$tmp/err"' "duplicate among 100k columns: $(cat "$tmp/err")"

# --- help everywhere ---------------------------------------------------------------------------
for args in "--help" "eval --help" "eval ndf --help" "validate --help"; do
  ok '"$mfkit" $args >"$tmp/help" 2>&1 && grep -q usage "$tmp/help"' "--help for '$args'"
done
ok '"$mfkit" --version | grep -q "^mfkit "' "--version"

# --- validate: table, JSON, atomic JSON file -------------------------------------------------
ok '"$mfkit" validate --quiet --json-file "$tmp/report.json" >"$tmp/table"' "validate passes"
ok 'grep -q "all checks passed" "$tmp/table"' "validate table"
ok '[ "$(grep -c "\"passed\": true" "$tmp/report.json")" -ge 9 ]' "validate JSON: every check passed"
ok '[ -z "$(ls "$tmp" | grep tmp)" ]' "no temporary files left"
ok '[ "$(stat -c %a "$tmp/report.json")" = "$(printf %o $((0666 & ~0$(umask))))" ]' "report has the usual permissions, not mkstemp's 0600"
ok '! "$mfkit" validate --quiet --json-file /nonexistent-dir/r.json >/dev/null 2>"$tmp/err" && grep -q "nonexistent-dir" "$tmp/err"' "validate JSON to a bad path fails with the path"
if [ -x /usr/bin/python3 ]; then
  ok '"$mfkit" validate --quiet --json | /usr/bin/python3 -c "import json,sys; d=json.load(sys.stdin); assert d[\"passed\"] and len(d[\"checks\"])>=8"' "validate --json parses"
fi

finish test_cli
