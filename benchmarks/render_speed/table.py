"""The table of benchmarks/render_speed/dome_master.sh: per run its CPU time
(user + sys), that time over the reference's, and its mean relative error
against the reference over the pixels whose R+G+B is above 1 % of the
reference's peak (`aurora_tools.image_compare.metrics`, threshold 0.01).

    .venv/bin/python benchmarks/render_speed/table.py OUT_DIR
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
from aurora_tools import image_compare  # noqa: E402
from aurora_tools.exr_io import read_rgba  # noqa: E402


def cpu(path: Path) -> tuple[float, float, int]:
    user, system, wall, kb = path.read_text().split()[:4]
    return float(user) + float(system), float(wall), int(kb)


def main() -> int:
    out = Path(sys.argv[1])
    ref = read_rgba(out / "ref-old-64.exr")
    ref_cpu, ref_wall, ref_kb = cpu(out / "ref-old-64.time")
    print(f"reference: old build, 64 spp: {ref_cpu:.1f} CPU-s ({ref_wall:.1f} s wall, {ref_kb / 1024:.0f} MiB peak)")
    print(f"{'run':<8} {'spp':>4} {'CPU s':>8} {'x ref CPU':>10} {'mean rel err':>13} {'bright px':>10} {'flux':>8}")
    for name in ["old-1", "old-2", "old-4", "old-8", "new-1", "new-2", "new-4"]:
        if not (out / f"{name}.exr").exists():
            continue
        c, _, _ = cpu(out / f"{name}.time")
        m = image_compare.metrics(read_rgba(out / f"{name}.exr"), ref, threshold=0.01)
        build, spp = name.split("-")
        print(f"{build:<8} {spp:>4} {c:>8.1f} {c / ref_cpu:>10.4f} {100 * m['mean_rel_err']:>12.3f}% "
              f"{m['bright_pixels']:>10} {m['flux_ratio']:>8.5f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
