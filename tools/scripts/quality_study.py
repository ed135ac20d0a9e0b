#!/usr/bin/env python3
"""The quality signal and the reported covariance against the truth, from `beamfield --json track`
reports (each run's `per_scan` records), with no beamfield code: the tables of
docs/localization.md ("The lost signal over buildings and real odometry", "Honest covariance").

Each input is LABEL=REPORT.json, where LABEL is `building/odometry` (e.g. `intel/wheels-mild`,
`intel-real/real`); the building is what the tuning/holdout split names.

  quality_study.py sweep --tune B1,B2 FILES...   the decision of beamfield::mcl::quality replayed
      on the recorded inputs (explained / short / through shares, likelihood per beam, spread)
      for a grid of thresholds: false Lost on clean runs and detection of excursions, on the
      tuning buildings and on the others. Exact for runs with resetting off (the signal then
      only reports; it does not change the run). --clutter and --through give the values of
      clutter_share and lost_through to try, --others-fixed keeps the other three at their
      defaults, --kidnap LABEL=REPORT.json adds kidnaps (resetting off) replayed: Lost within 5.
  quality_study.py table FILES...   the states the runs reported themselves, per building.
  quality_study.py covariance FILES...   share of the tracked errors inside the reported 95 %
      ellipse, and the NEES, per building.
  quality_study.py kidnap REPORT.json...   for `track --kidnap SCAN` reports: per run, the scans
      from the kidnapping to the first update reporting Uncertain or Lost ("flagged"), to the
      first reporting Lost, and to "found" (the first of 10 scans in a row within 0.2 m and 5°).

Definitions (as in docs/localization.md):
- a run is clean when its error never exceeds 0.5 m at a scan with a truth;
- a false Lost is an update reporting Lost in a clean run (an alarm with nothing wrong);
- an excursion starts at a scan with a truth whose error exceeds 0.5 m after one within 0.5 m
  (or at the first scan): flagged when an update from that scan to 5 scans later reports
  Uncertain or Lost (and "Lost within 5" when one reports Lost).
"""

import argparse
import json
import math
import sys

LOST_M = 0.5
WITHIN = 5
# Recording durations (hours), from the logs' time stamps (the raw-odometry run: its anchors'
# time stamps, scans 40-2703); Belgioioso's stamps are printed to 6 digits and give none.
HOURS = {
    "intel": 0.736,
    "intel-real": 0.731,
    "acapulco": 0.379,
    "edmonton": 0.197,
    "belgioioso": None,
}

DEFAULT = dict(
    clutter=0.5,
    lost_explained=0.35,
    lost_dropping=0.5,
    dropping_nats=0.25,
    fall=0.4,
    lost_after=3,
    tracking_explained=0.65,
    spread_m=0.25,
    spread_rad=0.15,
    concentration=0.5,
    through=1.0,
)


def load(items):
    runs = []
    for item in items:
        label, path = item.split("=", 1)
        building, odometry = label.split("/", 1)
        with open(path) as f:
            report = json.load(f)
        for r in report["runs"]:
            runs.append(
                dict(
                    building=building,
                    odometry=odometry,
                    seed=r["seed"],
                    alpha=report["odom_alphas"][0],
                    resetting=report["resetting"],
                    per=r["per_scan"],
                )
            )
    return runs


def num(v):
    return float("nan") if v is None else float(v)


def replay(per, t):
    """The states QualityState::observe would give with thresholds t (f64, not f32)."""
    fast = slow = e_avg = e_slow = t_avg = float("nan")
    streak = 0
    out = []

    def follow(avg, v, rate):
        if not math.isfinite(v):
            return avg
        if math.isnan(avg):
            return v
        return avg + rate * (v - avg)

    for rec in per:
        fit = [num(v) for v in rec["fit"]]
        ln_beam = num(rec["ln_beam"])
        spread_m, spread_rad, conc = (num(v) for v in rec["spread"])
        fast = follow(fast, ln_beam, 0.3)
        slow = follow(slow, ln_beam, 0.02)
        if math.isfinite(fit[0]):
            rest = 1.0 - max(0.0, min(fit[1], t["clutter"]))
            e = min(1.0, max(0.0, fit[0] / rest)) if rest > 0 else 0.0
        else:
            e = float("nan")
        e_avg = follow(e_avg, e, 0.5)
        e_slow = follow(e_slow, e, 0.02)
        t_avg = follow(t_avg, fit[2], 0.5)
        wide = not (
            spread_m <= t["spread_m"]
            and spread_rad <= t["spread_rad"]
            and conc >= t["concentration"]
        )
        drop = max(slow - fast, 0.0) if math.isfinite(slow) and math.isfinite(fast) else 0.0
        if math.isnan(e_avg):
            state = "uncertain"
        elif (
            e_avg < t["lost_explained"]
            or (e_avg < t["lost_dropping"] and drop > t["dropping_nats"])
            or e_slow - e_avg > t["fall"]
            or t_avg > t["through"]
        ):
            state = "lost"
        elif e_avg < t["tracking_explained"] or wide:
            state = "uncertain"
        else:
            state = "tracking"
        if state == "lost":
            streak += 1
            if streak < t["lost_after"]:
                state = "uncertain"
        else:
            streak = 0
        out.append(state)
    return out


def judge(run, states):
    per = run["per"]
    errs = [(i, rec["error_m"]) for i, rec in enumerate(per) if rec["error_m"] is not None]
    clean = all(e <= LOST_M for _, e in errs)
    false_lost = sum(1 for s in states if s == "lost") if clean else 0
    excursions = flagged = lost5 = 0
    prev_ok = True
    for i, e in errs:
        if e > LOST_M and prev_ok:
            excursions += 1
            scan = per[i]["scan"]
            window = [
                s for rec, s in zip(per[i:], states[i:]) if rec["scan"] <= scan + WITHIN
            ]
            flagged += any(s in ("uncertain", "lost") for s in window)
            lost5 += any(s == "lost" for s in window)
        prev_ok = e <= LOST_M
    return dict(
        clean=clean,
        false_lost=false_lost,
        false_runs=int(false_lost > 0),
        excursions=excursions,
        flagged=flagged,
        lost5=lost5,
        updates=len(per),
    )


def summarize(runs, results):
    s = dict(runs=len(runs), clean=0, false_lost=0, false_runs=0, excursions=0, flagged=0,
             lost5=0, hours=0.0, hours_known=True)
    for run, r in zip(runs, results):
        for k in ("false_lost", "false_runs", "excursions", "flagged", "lost5"):
            s[k] += r[k]
        if r["clean"]:
            s["clean"] += 1
            h = HOURS.get(run["building"])
            if h is None:
                s["hours_known"] = False
            else:
                s["hours"] += h
    return s


def fmt(s):
    rate = (
        f"{s['false_lost'] / s['hours']:.2f}" if s["hours"] > 0 else "—"
    ) + ("" if s["hours_known"] else " (*)")
    det = f"{s['flagged']}/{s['excursions']}" + (
        f" ({100.0 * s['flagged'] / s['excursions']:.0f} %)" if s["excursions"] else ""
    )
    return (
        f"| {s['runs']} | {s['clean']} | {s['false_lost']} | {s['false_runs']} | {rate} | {det} | "
        f"{s['lost5']}/{s['excursions']} |"
    )


HEADER = (
    "| runs | clean runs | false Lost (updates) | clean runs with one | false Lost per hour | "
    "excursions flagged within 5 | Lost within 5 |\n|---|---|---|---|---|---|---|"
)


def load_kidnaps(items):
    """LABEL=REPORT.json of `track --kidnap SCAN` runs (resetting off): (building, scan, per)."""
    out = []
    for item in items:
        label, path = item.split("=", 1)
        building = label.split("/", 1)[0]
        with open(path) as f:
            report = json.load(f)
        k = report.get("kidnap")
        if k is None:
            sys.exit(f"{path}: not a --kidnap run")
        if report.get("resetting"):
            sys.exit(f"{path}: a kidnap replayed must have resetting off")
        for r in report["runs"]:
            out.append((building, k, r["per_scan"]))
    return out


def kidnap_lost_within(kidnaps, t, within=5):
    """Kidnaps whose replayed states report Lost within `within` scans, and their count."""
    hit = 0
    for _, k, per in kidnaps:
        states = replay(per, t)
        hit += any(s == "lost" and rec["scan"] - k <= within
                   for rec, s in zip(per, states) if rec["scan"] >= k)
    return hit, len(kidnaps)


def cmd_sweep(a):
    runs = load(a.files)
    tune = set(a.tune.split(","))
    kidnaps = load_kidnaps(a.kidnap)
    floats = lambda text: [float(x) for x in text.split(",")]
    grid = []
    for clutter in floats(a.clutter):
        for through in floats(a.through):
            for lost_explained in (0.35,) if a.others_fixed else (0.25, 0.35, 0.45):
                for fall in (0.4,) if a.others_fixed else (0.3, 0.4, 0.5, 1.0):
                    for lost_after in (3,) if a.others_fixed else (2, 3, 4):
                        grid.append(dict(DEFAULT, clutter=clutter, through=through,
                                         lost_explained=lost_explained, fall=fall,
                                         lost_after=lost_after))
    parts = {
        "tuning": [r for r in runs if r["building"] in tune],
        "holdout": [r for r in runs if r["building"] not in tune],
    }
    kparts = {
        "tuning": [x for x in kidnaps if x[0] in tune],
        "holdout": [x for x in kidnaps if x[0] not in tune],
    }
    print(f"tuning: {sorted(tune)}; holdout: {sorted({r['building'] for r in parts['holdout']})}")
    extra = " kidnaps Lost within 5 |" if kidnaps else ""
    print("| part | clutter_share | lost_through | lost_explained | lost_explained_fall | lost_after |"
          + HEADER[1:].split("\n")[0] + extra)
    print("|---|---|---|---|---|---" + HEADER.split("\n")[1] + ("---|" if kidnaps else ""))
    for t in grid:
        for part in ("tuning", "holdout") if a.both else ("tuning",):
            rs = parts[part]
            res = [judge(r, replay(r["per"], t)) for r in rs]
            s = summarize(rs, res)
            row = (f"| {part} | {t['clutter']} | {t['through']} | {t['lost_explained']} | {t['fall']} "
                   f"| {t['lost_after']} " + fmt(s))
            if kidnaps:
                hit, n = kidnap_lost_within(kparts[part], t)
                row += f" {hit}/{n} |"
            print(row)


def cmd_table(a):
    runs = load(a.files)
    groups = {}
    for r in runs:
        groups.setdefault((r["building"], r["odometry"], r["alpha"], r["resetting"]), []).append(r)
    print("| building | odometry | filter α | resetting " + HEADER[1:].split("\n")[0])
    print("|---|---|---|---" + HEADER.split("\n")[1])
    for key, rs in groups.items():
        res = [judge(r, [rec["quality"] for rec in r["per"]]) for r in rs]
        s = summarize(rs, res)
        print(f"| {key[0]} | {key[1]} | {key[2]} | {'on' if key[3] else 'off'} " + fmt(s))


CHI2_95_2D = 5.991464547107979


def cmd_covariance(a):
    runs = load(a.files)
    groups = {}
    for r in runs:
        groups.setdefault((r["building"], r["odometry"]), []).append(r)
    print(
        "| building | odometry | tracked errors | inside the 95 % ellipse | NEES (x, y; ideal 2) median / mean | "
        "not tracking: reported σ (m) median | shrank while not tracking |"
    )
    print("|---|---|---|---|---|---|---|")
    for key, rs in groups.items():
        inside = n = 0
        nees = []
        sig_off = []
        shrank = 0
        for r in rs:
            prev = None
            for rec in r["per"]:
                cov = rec[a.field]
                k2 = a.scale * a.scale
                f2 = a.floor * a.floor
                xx, xy, yy = k2 * cov[0] + f2, k2 * cov[1], k2 * cov[2] + f2
                if rec["quality"] != "tracking":
                    sig_off.append(math.sqrt(max(xx, yy, 0.0)))
                    if prev is not None and max(xx, yy) < prev:
                        shrank += 1
                    prev = max(xx, yy)
                else:
                    prev = None
                if rec["error_m"] is None or rec["quality"] != "tracking" or rec.get("truth") is None:
                    continue
                dx = rec["pose"][0] - rec["truth"][0]
                dy = rec["pose"][1] - rec["truth"][1]
                det = xx * yy - xy * xy
                if det <= 0:
                    q = float("inf")
                else:
                    q = (yy * dx * dx - 2 * xy * dx * dy + xx * dy * dy) / det
                nees.append(q)
                inside += q <= CHI2_95_2D
                n += 1
        nees.sort()
        med = nees[len(nees) // 2] if nees else float("nan")
        finite = [q for q in nees if math.isfinite(q)]
        mean = sum(finite) / len(finite) if finite else float("nan")
        sig_off.sort()
        so = f"{sig_off[len(sig_off) // 2]:.3f}" if sig_off else "—"
        share = f"{100.0 * inside / n:.1f} %" if n else "—"
        print(f"| {key[0]} | {key[1]} | {n} | {share} | {med:.2f} / {mean:.2f} | {so} | {shrank} |")


FOUND_M = 0.2
FOUND_DEG = 5.0
FOUND_SCANS = 10


def cmd_kidnap(a):
    print("| report | runs | flagged within 5 | Lost within 5 | scans to Lost (median) | found within 50 | scans to found (median) |")
    print("|---|---|---|---|---|---|---|")
    for path in a.files:
        with open(path) as f:
            report = json.load(f)
        k = report.get("kidnap")
        if k is None:
            sys.exit(f"{path}: not a --kidnap run")
        flagged, lost, found = [], [], []
        for r in report["runs"]:
            per = [p for p in r["per_scan"] if p["scan"] >= k]
            first = lambda states: next((p["scan"] - k for p in per if p["quality"] in states), None)
            flagged.append(first(("uncertain", "lost")))
            lost.append(first(("lost",)))
            f = None
            for i in range(len(per) - FOUND_SCANS + 1):
                w = per[i:i + FOUND_SCANS]
                if all(q["error_m"] is not None and q["error_m"] <= FOUND_M
                       and q["heading_error_deg"] <= FOUND_DEG for q in w):
                    f = per[i]["scan"] - k
                    break
            found.append(f)
        n = len(report["runs"])

        def within(v, m):
            return sum(1 for x in v if x is not None and x <= m)

        def median(v):
            xs = sorted(math.inf if x is None else x for x in v)
            if not xs:
                return "—"
            mid = (xs[(len(xs) - 1) // 2] + xs[len(xs) // 2]) / 2
            return "never" if math.isinf(mid) else f"{mid:g}"

        print(f"| {path} | {n} | {within(flagged, 5)} of {n} | {within(lost, 5)} of {n} | {median(lost)} "
              f"| {within(found, 50)} of {n} | {median(found)} |")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("sweep")
    s.add_argument("--tune", required=True, help="buildings the thresholds are chosen on")
    s.add_argument("--both", action="store_true", help="print the holdout rows too")
    s.add_argument("--clutter", default="0,0.3,0.5,0.7", help="clutter_share values (comma list)")
    s.add_argument("--through", default="1.0",
                   help="lost_through values (comma list; 1.0: off)")
    s.add_argument("--others-fixed", action="store_true",
                   help="lost_explained 0.35, lost_explained_fall 0.4, lost_after 3 only")
    s.add_argument("--kidnap", action="append", default=[], metavar="LABEL=REPORT.json",
                   help="a `track --kidnap SCAN` report (resetting off) whose kidnaps are "
                        "replayed: Lost within 5 scans per part")
    s.add_argument("files", nargs="+")
    s.set_defaults(f=cmd_sweep)
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+")
    t.set_defaults(f=cmd_table)
    c = sub.add_parser("covariance")
    c.add_argument("--field", default="covariance", help="the per_scan field holding xx, xy, yy")
    c.add_argument("--floor", type=float, default=0.0,
                   help="a what-if: add this σ (m) to x and y in quadrature")
    c.add_argument("--scale", type=float, default=1.0, help="a what-if: scale the σ by this")
    c.add_argument("files", nargs="+")
    c.set_defaults(f=cmd_covariance)
    k = sub.add_parser("kidnap")
    k.add_argument("files", nargs="+")
    k.set_defaults(f=cmd_kidnap)
    a = p.parse_args()
    a.f(a)


if __name__ == "__main__":
    sys.exit(main())
