"""Compare two compare_global_pose JSON runs: certified fractions (certify=True) and medians per row.

    python bench/compare_global_pose_runs.py bench/out/OLD.json bench/out/NEW.json

prints a Markdown table (rows of NEW; certified count and median time with certify in each run, their
ratio), the rows whose misses differ, and how many rows certify more, fewer or the same."""
import json, sys, statistics
a = {r["row"]: r for r in json.load(open(sys.argv[1]))["results"]}
b = {r["row"]: r for r in json.load(open(sys.argv[2]))["results"]}
up = down = same = 0
ratios = []
print(f"| row | certified before | now | median µs before | now | ratio |")
print("|---|---:|---:|---:|---:|---:|")
for name, rb in b.items():
    ra = a.get(name)
    cb = rb["certify"]
    if ra is None:
        print(f"| {name} | — | {cb['certified_fraction']*rb['scenes']:.0f}/{rb['scenes']} | — | {cb['median_us']:.0f} | — |")
        continue
    ca = ra["certify"]
    na, nb = round(ca["certified_fraction"] * ra["scenes"]), round(cb["certified_fraction"] * rb["scenes"])
    up += nb > na; down += nb < na; same += nb == na
    ratio = cb["median_us"] / ca["median_us"]
    if rb["data"] == "points": ratios.append(ratio)
    print(f"| {name} | {na}/{ra['scenes']} | {nb}/{rb['scenes']} | {ca['median_us']:.0f} | {cb['median_us']:.0f} | {ratio:.2f} |")
    for key in ("misses",):
        if ra[key] != rb[key]:
            print(f"  !! {name}: {key} {ra[key]} -> {rb[key]}")
print(f"\ncertified up on {up} rows, down on {down}, same on {same}; point rows certify-median ratio "
      f"{min(ratios):.2f}-{max(ratios):.2f} (median {statistics.median(ratios):.2f})" if ratios else "")
