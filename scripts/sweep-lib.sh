# shellcheck shell=sh
# scripts/sweep-lib.sh: helpers shared by scripts/sweep, scripts/sweep-plot
# and scripts/validate.sh (sourced, not run). POSIX sh + awk only: no
# python, no jq. CSV columns are always found by their header name.

# awk functions, prepended to awk programs:
#   csv_split(line, f)  splits one RFC 4180 line into f[1..n], unquoted; returns n
#   csv_q(s)            s quoted for CSV when it holds a comma, quote or newline
#   num(s)              1 when s is a plain finite number
# shellcheck disable=SC2016
AWK_CSV='
function csv_split(line, f,    n, i, c, s, q, L) {
	n = 0; s = ""; q = 0; L = length(line)
	for (i = 1; i <= L; i++) {
		c = substr(line, i, 1)
		if (q) {
			if (c == "\"") {
				if (substr(line, i + 1, 1) == "\"") { s = s "\""; i++ } else q = 0
			} else s = s c
		} else if (c == "\"") q = 1
		else if (c == ",") { f[++n] = s; s = "" }
		else if (c != "\r") s = s c
	}
	f[++n] = s
	return n
}
function csv_q(s,    t) {
	if (s !~ /[,"\n]/) return s
	t = s; gsub(/"/, "\"\"", t)
	return "\"" t "\""
}
function num(s) { return s ~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$/ }
'

# json_flat FILE: every scalar of a JSON document as "dotted.path<TAB>value"
# (array elements by index from 0: size.0, per_frame.1.fps; strings
# unquoted; null printed as null).
json_flat() {
	awk '
	{ buf = buf $0 "\n" }
	function emit(v,    p, k) {
		if (d < 1) return
		p = cur[1]
		for (k = 2; k <= d; k++) p = p "." cur[k]
		print p "\t" v
	}
	END {
		n = length(buf); d = 0; i = 1
		while (i <= n) {
			c = substr(buf, i, 1)
			if (c == "{" || c == "[") {
				d++; ty[d] = c
				if (c == "[") cur[d] = 0; else { cur[d] = ""; expkey = 1 }
				i++
			} else if (c == "}" || c == "]") { d--; i++ }
			else if (c == ",") {
				if (ty[d] == "[") cur[d]++; else expkey = 1
				i++
			} else if (c == ":") { expkey = 0; i++ }
			else if (c == " " || c == "\n" || c == "\t" || c == "\r") i++
			else if (c == "\"") {
				s = ""; j = i + 1
				while (j <= n) {
					ch = substr(buf, j, 1)
					if (ch == "\\") { s = s substr(buf, j + 1, 1); j += 2; continue }
					if (ch == "\"") break
					s = s ch; j++
				}
				i = j + 1
				if (ty[d] == "{" && expkey) { cur[d] = s; expkey = 0 } else emit(s)
			} else {
				j = i
				while (j <= n && index(",}] \n\t\r", substr(buf, j, 1)) == 0) j++
				emit(substr(buf, i, j - i)); i = j
			}
		}
	}' "$1"
}

# csv_cols FILE COL...: the named columns of every data row of a CSV file as
# tab-separated lines (a missing column gives empty fields).
csv_cols() {
	_f=$1
	shift
	awk -v want="$*" "$AWK_CSV"'
	NR == 1 {
		n = csv_split($0, h); for (i = 1; i <= n; i++) if (!(h[i] in col)) col[h[i]] = i
		nw = split(want, w, " ")
		next
	}
	$0 != "" {
		csv_split($0, f); line = ""
		for (k = 1; k <= nw; k++) line = line (k > 1 ? "\t" : "") (w[k] in col ? f[col[w[k]]] : "")
		print line
	}' "$_f"
}

# point_ok FILE ID: FILE is a finished point's CSV, whole: a header whose
# first column is id, then exactly one row with as many fields whose id is
# ID. (A point writes it atomically; this catches one damaged or emptied
# afterwards, which would otherwise count as done and never run again.)
point_ok() {
	[ -s "$1" ] || return 1
	awk -v id="$2" "$AWK_CSV"'
	NR == 1 { nh = csv_split($0, h); ok = h[1] == "id"; next }
	NR == 2 { n = csv_split($0, f); ok = ok && n == nh && f[1] == id; next }
	{ ok = 0 }
	END { exit !(ok && NR == 2) }' "$1"
}

# csv_union OUT FILE...: concatenates CSV files into OUT (atomically),
# matching columns by header name: the header is the union of all headers in
# order of first appearance; a file without a column gets empty fields.
csv_union() {
	_out=$1
	shift
	awk "$AWK_CSV"'
	FNR == 1 {
		nf = csv_split($0, h)
		for (i = 1; i <= nf; i++) {
			fmap[FILENAME, i] = h[i]
			if (!(h[i] in have)) { have[h[i]] = 1; hdr[++nh] = h[i] }
		}
		nfile[FILENAME] = nf
		next
	}
	$0 != "" {
		n = csv_split($0, f); nr++
		for (i = 1; i <= n; i++) val[nr, fmap[FILENAME, i]] = f[i]
	}
	END {
		line = ""
		for (k = 1; k <= nh; k++) line = line (k > 1 ? "," : "") csv_q(hdr[k])
		print line
		for (r = 1; r <= nr; r++) {
			line = ""
			for (k = 1; k <= nh; k++) line = line (k > 1 ? "," : "") csv_q(val[r, hdr[k]])
			print line
		}
	}' "$@" >"$_out.tmp.$$"
	mv -f "$_out.tmp.$$" "$_out"
}

# sh_q STRING: STRING quoted for a POSIX shell, in single quotes (a single
# quote inside as '\''): for the commands the sweep writes into scripts
# (sweep.slurm) and prints to be pasted.
sh_q() {
	printf "'%s'" "$(printf '%s\n' "$1" | sed "s/'/'\\\\''/g")"
}

# is_true VALUE: a config boolean that means true (YAML spellings and 1).
is_true() {
	case $1 in true | True | TRUE | yes | Yes | on | On | 1) return 0 ;; *) return 1 ;; esac
}
