#!/usr/bin/env python3
# Re-makes the real-log table of docs/leveling-results.md: every leveling method on short
# windows of the two PX4 logs, as differences from a long plain-mean reference (armed idle
# before take-off, motors off after landing; segment times found from the logs' arming,
# take-off and land-detector topics, see docs/leveling-results.md).
# Usage: python3 docs/leveling/real_logs.py [NAVTWIN_BINARY]  (default build/bin/navtwin;
# data from $NAVTWIN_DATA or ../shared/data)
import json, math, os, subprocess, sys
NAV = sys.argv[1] if len(sys.argv) > 1 else 'build/bin/navtwin'
D = os.path.join(os.environ.get('NAVTWIN_DATA', '../shared/data'), 'px4-ulog') + '/'
METHODS = ['plain_mean', 'period_average', 'filter', 'batch']
def level(f, s, w, extra=''):
    cmd = f"navtwin level --imu {f} --start_s {s:g} --window_s {w:g}{extra} --format=json"
    p = subprocess.run(f"{NAV} level --imu {D}{f} --start_s {s:g} --window_s {w:g}{extra} --format=json", shell=True, capture_output=True, text=True)
    return cmd, p.returncode, (json.loads(p.stdout) if p.returncode == 0 else None), p.stderr.strip()
LOGS = {
 'battery_brownout.ulg': dict(
    refs={'off_after_landing': (75.1, 0.9), 'idle_before_takeoff': (0.5, 2.8)},
    segs=[('idle before take-off', 0.5, 3.3, 'idle_before_takeoff'), ('ramp-up', 3.4, 4.8, 'idle_before_takeoff'),
          ('idle after landing', 73.1, 75.0, 'off_after_landing'), ('motors off', 75.1, 76.0, 'off_after_landing')]),
 'gps_interference.ulg': dict(
    refs={'off_after_landing': (61.5, 0.75), 'idle_before_takeoff': (0.0, 3.7)},
    segs=[('idle before take-off', 0.0, 3.7, 'idle_before_takeoff'), ('ramp-up', 3.7, 5.8, 'idle_before_takeoff'),
          ('motors off', 61.5, 62.25, 'off_after_landing')]),
}
for f, cfg in LOGS.items():
    refs = {}
    for name, (s, w) in cfg['refs'].items():
        cmd, rc, j, err = level(f, s, w)
        m = j['methods']['plain_mean']
        refs[name] = (m['roll_deg'], m['pitch_deg'])
        print(f"REF {f} {name}: `{cmd}` plain_mean roll {m['roll_deg']:.3f} pitch {m['pitch_deg']:.3f} (1s {m['roll_sigma_deg']:.3f}/{m['pitch_sigma_deg']:.3f}) samples {j['samples']} rate {j['rate_hz']:.2f}")
    for seg, a, b, refname in cfg['segs']:
        rr, rp = refs[refname]
        for w in (0.2, 1.0):
            step = 0.2 if w == 0.2 else 0.5
            starts = []; s = a
            while s + w <= b + 1e-9: starts.append(round(s, 3)); s += step
            if not starts: continue
            stats = {m: [] for m in METHODS}; fb = {m: 0 for m in METHODS}; refused = 0; periods = {m: [] for m in METHODS}
            for s in starts:
                cmd, rc, j, err = level(f, s, w)
                if rc != 0:
                    refused += 1; print(f"   refused {cmd}: {err.splitlines()[0] if err else rc}"); continue
                for m in METHODS:
                    e = j['methods'][m]
                    stats[m].append((e['roll_deg'] - rr, e['pitch_deg'] - rp, e['roll_sigma_deg'], e['pitch_sigma_deg']))
                    if e['fallback']: fb[m] += 1
                    if e['vib_freq_hz'] > 0: periods[m].append(e['vib_freq_hz'])
            print(f"SEG {f} | {seg} {a}-{b} s | window {w} s | starts {starts[0]}..{starts[-1]} step {step} ({len(starts)} windows, {refused} refused) | ref {refname}")
            for m in METHODS:
                v = stats[m]
                if not v: continue
                n = len(v)
                mr = sum(x[0] for x in v)/n; mp = sum(x[1] for x in v)/n
                rmsr = math.sqrt(sum(x[0]**2 for x in v)/n); rmsp = math.sqrt(sum(x[1]**2 for x in v)/n)
                mxr = max(abs(x[0]) for x in v); mxp = max(abs(x[1]) for x in v)
                sr = math.sqrt(sum(x[2]**2 for x in v)/n); sp = math.sqrt(sum(x[3]**2 for x in v)/n)
                fq = periods[m]; fqs = f"{min(fq):.1f}-{max(fq):.1f} Hz" if fq else "-"
                print(f"   {m:15s} roll mean {mr:+.3f} rms {rmsr:.3f} max {mxr:.3f} | pitch mean {mp:+.3f} rms {rmsp:.3f} max {mxp:.3f} | rms sigma {sr:.3f}/{sp:.3f} | fallbacks {fb[m]}/{n} | freq {fqs}")
