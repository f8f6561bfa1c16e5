"""Write the packaged per-task configs, configs/<method>/<task>.yaml, for every one of sgr's 32 tasks
from each of sgr's methods' own template (`Problem.packaged`, evolve/methods/packaged.py; a
developer tool: it is not installed). A method of sgr's that declares a template gets its configs
with no edit here.

Every config of a method is its template with the task's name and episode length filled in: the
paper's settings (generations 250; SGR and direct NEAT 128 genomes, nested NEAT 12 bodies x 12
controllers; 5x5 bodies) and the honest evaluation every packaged config evolves under
(docs/EVOLVE.md "Robust evaluation").

Hand-written variants (quick.yaml, <task>-10x10.yaml, direct/<task>-per-cell.yaml) are not
generated. tests/evolve/runs/test_packaged_configs.py checks that the committed files are what
this script writes, so edit a method's template and run:

    python tools/gen_configs.py          # rewrite the files
    python tools/gen_configs.py --check  # exit 1 naming the files that differ
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from evolve.methods import BUILTIN as BUILTIN_METHODS  # noqa: E402
from evolve.methods import METHODS  # noqa: E402
from tasks.specs import BUILTIN  # noqa: E402


def generated() -> dict[Path, str]:
    """Every generated config: its path under configs/ -> its text."""
    return {Path(name) / f"{task}.yaml": problem.packaged.render(task)
            for name, problem in METHODS.items() if name in BUILTIN_METHODS and problem.packaged is not None
            for task in sorted(BUILTIN)}


def main(argv: list[str] | None = None) -> int:
    """Write the configs (or, with --check, list those that differ from the templates)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 if a file differs")
    p.add_argument("--out", type=Path, default=ROOT / "configs", help="the configs folder")
    args = p.parse_args(argv)
    stale = []
    for rel, text in generated().items():
        path = args.out / rel
        if path.is_file() and path.read_text() == text:
            continue
        stale.append(str(rel))
        if not args.check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
    if args.check and stale:
        print(f"{len(stale)} configs differ from tools/gen_configs.py's templates: {', '.join(stale)}; "
              "run python tools/gen_configs.py", file=sys.stderr)
        return 1
    print(f"{'checked' if args.check else 'wrote'} {len(stale) if not args.check else len(generated())} "
          f"configs in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
