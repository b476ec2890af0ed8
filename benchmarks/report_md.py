"""Print the Markdown tables of docs/benchmarks.md from a bench folder and a suite folder.

    python benchmarks/report_md.py bench_out/latest bench_out/suite
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from dualarm_qp.bench.report import format_table
from dualarm_qp.bench.suite import format_suite_table


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    bench = json.loads((Path(args[0]) / "bench.json").read_text())
    m = bench["meta"]["machine"]
    print(f"machine: {m['cpu']}, {m['cpus']} cpus, {m['system']}, Python {m['python']}, "
          f"numpy {m['numpy']}, qpsolvers {m['qpsolvers']}; load average at start "
          f"{[round(x, 2) for x in m['load_average']]}; {m['time']}\n")
    print(format_table(bench["rows"], markdown=True))
    if len(args) > 1:
        suite = json.loads((Path(args[1]) / "suite.json").read_text())
        for profile in dict.fromkeys(r["profile"] for r in suite["rows"]):
            print(f"\nprofile {profile}, {suite['instances']} instances\n")
            print(format_suite_table([r for r in suite["rows"] if r["profile"] == profile],
                                     markdown=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
