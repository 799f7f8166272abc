import json, sys
D = 'bench/results/2026-11-27-pose-certificate-lens/'
full = {r['row']: r for r in json.load(open(D+'compare_global_pose_full.json'))['results']}
before = {r['row']: r for r in json.load(open(D+'compare_global_pose_lens.json'))['results']}
now = {r['row']: r for r in json.load(open(sys.argv[1]))['results']}
print("| lens row | certified before | certified now | median with certify, before → now | pinhole pair certified | pinhole median |")
print("|---|---:|---:|---:|---:|---:|")
fmt = lambda x: f"{x/1000:.1f} ms" if x is not None else "—"
for name, r in now.items():
    if not name.startswith('lens'):
        continue
    c = r['certify']; b = before.get(name, full.get(name, {})).get('certify', {})
    pair = r.get('pinhole_pair'); p = full.get(pair, {}).get('certify', {})
    cnt = lambda d: round(r['scenes']*d['certified_fraction']) if 'certified_fraction' in d else '—'
    print(f"| {name} | {cnt(b)}/50 | {cnt(c)}/50 | {fmt(b.get('median_us'))} → {fmt(c.get('median_us'))} | {cnt(p)}/50 | {fmt(p.get('median_us'))} |")
