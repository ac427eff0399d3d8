#!/usr/bin/env python3
"""timeline-check.py: checks a saarsim --timeline file (docs/observe.md).

  timeline-check.py TIMELINE.json [REPORT.json] [--full FULL.json]

Structure: a trace-event object whose traceEvents are metadata ("M") and
complete ("X") events with name, pid, tid, ts >= 0, dur >= 0 and args; as
many X events as otherData.events; every X event starting inside
otherData.window; on each track (pid, tid) no two spans overlap.

With REPORT.json (the same run's --report) and a timeline of the whole run
(no window, not capped): per RTP and unit kind, the ops and their issue
cycles equal the counters rtp<r>.<kind>.ops and .busy_cycles; per RTP the
threads' running, waiting_memory and waiting_unit spans add up to
rtp<r>.threads.<state>_ps (to the rounding of the 3 decimals, half a
thousandth of a cycle per span); the L1 miss spans of each L1 equal its fills;
the SDRAM data-bus spans equal the row segments and add up to busy_ns; the
host-bus spans equal its transfers and bytes.

With --full FULL.json (the same run's timeline without a window): the
windowed timeline holds exactly the full one's unit ops, L1 misses, SDRAM
and host-bus spans that start in the window, and its thread spans are the
full one's clipped to it.

Prints "ok: ..." and exits 0, or one line per problem and exits 1; a file
that cannot be read (missing, not JSON) is one line and exit status 2.
"""
import json
import sys
from collections import Counter, defaultdict

TID_THREAD = 100000
TID_L1 = 1000000
STATES = ("running", "waiting_memory", "waiting_unit")
KINDS = ("rgs", "trav", "list", "isect")
L1S = ("shade", "kd", "list", "tri")
EPS = 0.0015  # cycles: ts and dur are written with 3 decimals

problems = []


def bad(msg):
    problems.append(msg)


def load(path):
    with open(path) as f:
        try:
            return json.load(f)
        except ValueError as e:
            raise ValueError(f"{path}: not JSON ({e})") from None


def spans(tl):
    """The X events, after checking every event's form."""
    if not isinstance(tl, dict) or not isinstance(tl.get("traceEvents"), list):
        bad("not a trace-event object with a traceEvents list")
        return []
    out = []
    for i, e in enumerate(tl["traceEvents"]):
        ph = e.get("ph")
        if ph == "M":
            if not isinstance(e.get("args"), dict) or "pid" not in e:
                bad(f"event {i}: metadata without pid or args")
            continue
        if ph != "X":
            bad(f"event {i}: phase {ph!r} (only M and X are written)")
            continue
        ok = isinstance(e.get("name"), str) and isinstance(e.get("pid"), int) and \
            isinstance(e.get("tid"), int) and isinstance(e.get("args"), dict)
        ts, dur = e.get("ts"), e.get("dur")
        if not ok or not isinstance(ts, (int, float)) or not isinstance(dur, (int, float)) \
                or ts < 0 or dur < 0:
            bad(f"event {i}: not a complete event with name, pid, tid, ts >= 0, dur >= 0, args")
            continue
        out.append(e)
    return out


def structure(tl, xs):
    od = tl.get("otherData", {})
    if od.get("events") != len(xs):
        bad(f"otherData.events {od.get('events')} but {len(xs)} X events")
    if od.get("capped") != (od.get("dropped_events", 0) > 0):
        bad("otherData.capped disagrees with dropped_events")
    if len(xs) > od.get("max_events", len(xs)):
        bad("more events than max_events")
    w0, w1 = od.get("window", [0, None])
    for e in xs:
        if e["ts"] < w0 or (w1 is not None and e["ts"] >= w1):
            bad(f"{e['name']} at {e['ts']} outside the window [{w0}, {w1})")
            break
    tracks = defaultdict(list)
    for e in xs:
        tracks[(e["pid"], e["tid"])].append(e)
    for key, es in tracks.items():
        es.sort(key=lambda e: e["ts"])
        for a, b in zip(es, es[1:]):
            if b["ts"] < a["ts"] + a["dur"] - EPS:
                bad(f"track {key}: {a['name']} at {a['ts']} (dur {a['dur']}) overlaps "
                    f"{b['name']} at {b['ts']}")
                break
    return od


def classify(e, nrtp):
    """('op', rtp, kind) | ('state', rtp, state) | ('l1', type) | ('sdram',) | ('host',)"""
    if e["pid"] < nrtp:
        if e["tid"] >= TID_THREAD:
            return ("state", e["pid"], e["name"])
        return ("op", e["pid"], e["args"].get("kind"))
    if e["tid"] >= TID_L1:
        return ("l1", e["args"].get("l1"))
    return ("sdram",) if e["tid"] == 1 else ("host",)


def near(a, b, tol):
    return abs(a - b) <= tol


def against_report(xs, od, r):
    if od["window"] != [0, None] or od["capped"]:
        bad("a report check needs a timeline of the whole run (no window, not capped)")
        return
    nrtp, period = od["rtps"], od["period_ps"]
    ctr = r["counters"]
    ops, busy = Counter(), Counter()
    st, nst = Counter(), Counter()
    l1, sd_n, sd_dur, hb_n, hb_bytes = Counter(), 0, 0.0, 0, 0
    for e in xs:
        c = classify(e, nrtp)
        if c[0] == "op":
            ops[c[1:]] += 1
            busy[c[1:]] += e["args"]["issue_cycles"]
            if not near(e["dur"], e["args"]["issue_cycles"], EPS):
                bad(f"{c[2]} op at {e['ts']}: dur {e['dur']} is not its issue cycles")
        elif c[0] == "state":
            st[c[1:]] += e["dur"]
            nst[c[1:]] += 1
        elif c[0] == "l1":
            l1[c[1]] += 1
        elif c[0] == "sdram":
            sd_n += 1
            sd_dur += e["dur"]
        else:
            hb_n += 1
            hb_bytes += e["args"]["bytes"]
    for rtp in range(nrtp):
        for k in KINDS:
            want_ops = ctr[f"rtp{rtp}.{k}.ops"]
            want_busy = ctr[f"rtp{rtp}.{k}.busy_cycles"]
            if ops[(rtp, k)] != want_ops:
                bad(f"rtp{rtp}.{k}.ops: timeline {ops[(rtp, k)]}, report {want_ops}")
            if busy[(rtp, k)] != want_busy:
                bad(f"rtp{rtp}.{k}.busy_cycles: timeline {busy[(rtp, k)]}, report {want_busy}")
        for s in STATES:
            want = ctr[f"rtp{rtp}.threads.{s}_ps"]
            got = st[(rtp, s)] * period
            if not near(got, want, (nst[(rtp, s)] * 0.0005 + 0.001) * period):
                bad(f"rtp{rtp}.threads.{s}_ps: timeline {got:.0f}, report {want}")
    for k in KINDS:
        if sum(ops[(rtp, k)] for rtp in range(nrtp)) != r["units"][k]["ops"]:
            bad(f"units.{k}.ops: timeline and report differ")
        if sum(busy[(rtp, k)] for rtp in range(nrtp)) != r["units"][k]["busy_cycles"]:
            bad(f"units.{k}.busy_cycles: timeline and report differ")
    h = (r.get("memory") or {}).get("hierarchy")
    if not h:
        if l1 or sd_n or hb_n:
            bad("memory spans, but the report has no memory hierarchy")
        return
    for t in L1S:
        fills = h["l1"][t]["cache"]["fills"]
        if l1[t] != fills:
            bad(f"l1.{t}: {l1[t]} miss spans, report fills {fills}")
    sd = h["sdram"]
    segs = sd["row_hits"] + sd["row_empty"] + sd["row_conflicts"]
    if sd_n != segs:
        bad(f"sdram: {sd_n} bus spans, report {segs} row segments")
    if not near(sd_dur * period / 1000.0, sd["busy_ns"], 1.0 + sd_n * EPS * period / 1000.0):
        bad(f"sdram: bus spans {sd_dur * period / 1000.0:.1f} ns, report busy_ns {sd['busy_ns']}")
    hb = h.get("hostbus")
    if hb:
        if hb_n != hb["transfers"] or hb_bytes != hb["bytes"]:
            bad(f"hostbus: {hb_n} transfers / {hb_bytes} bytes, report {hb['transfers']} / "
                f"{hb['bytes']}")
    elif hb_n:
        bad("host-bus spans, but the report has no host bus")


def against_full(xs, od, full):
    fx = spans(full)
    fod = full.get("otherData", {})
    if fod.get("window") != [0, None] or fod.get("capped"):
        bad("--full needs a timeline of the whole run")
        return
    nrtp = od["rtps"]
    w0, w1 = od["window"]
    w1 = float("inf") if w1 is None else w1

    want, got = defaultdict(list), defaultdict(list)
    for e in fx:
        k = (e["pid"], e["tid"], e["name"])
        if classify(e, nrtp)[0] == "state":
            a, b = max(e["ts"], w0), min(e["ts"] + e["dur"], w1)
            if a < b:
                want[k].append((a, b - a))
        elif w0 <= e["ts"] < w1:
            want[k].append((e["ts"], e["dur"]))
    for e in xs:
        got[(e["pid"], e["tid"], e["name"])].append((e["ts"], e["dur"]))
    for k in set(want) | set(got):
        w, g = sorted(want[k]), sorted(got[k])
        if len(w) != len(g):
            bad(f"window: track {k}: {len(g)} spans, the full timeline has {len(w)} in it")
            return
        for x, y in zip(w, g):
            if not (near(x[0], y[0], 2 * EPS) and near(x[1], y[1], 2 * EPS)):
                bad(f"window: track {k}: span {y} where the full timeline has {x}")
                return


def main(argv):
    args, full = [], None
    i = 0
    while i < len(argv):
        if argv[i] == "--full" and i + 1 < len(argv):
            full = argv[i + 1]
            i += 2
        else:
            args.append(argv[i])
            i += 1
    if not 1 <= len(args) <= 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    tl = load(args[0])
    xs = spans(tl)
    od = structure(tl, xs)
    if not problems and len(args) == 2:
        against_report(xs, od, load(args[1]))
    if not problems and full:
        against_full(xs, od, load(full))
    for p in problems:
        print(p)
    if problems:
        return 1
    print(f"ok: {len(xs)} spans")
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] in (["-h"], ["--help"]):
        print(__doc__.strip())
        sys.exit(0)
    try:
        sys.exit(main(sys.argv[1:]))
    except (OSError, ValueError) as e:  # a file missing or not JSON: one line
        print(f"timeline-check.py: {e}", file=sys.stderr)
        sys.exit(2)
