"""``beatsync reproduce``: run the study's notebooks with papermill."""

from __future__ import annotations

import argparse
import sys

from ._common import add_json_flag, emit


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "reproduce",
        help="run the study's notebooks with papermill from a parameter file",
        description="Execute every notebook (or --only some) with the parameters of a "
        "parameter file; refuse parameters a notebook does not declare.",
    )
    p.add_argument("--params", default="params/paper.yaml", help="parameter file (YAML)")
    p.add_argument("--notebooks", default="notebooks", help="folder of the notebooks")
    p.add_argument(
        "--output", default="results/notebooks", help="folder for the executed notebooks"
    )
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these notebooks")
    p.add_argument(
        "--in-place",
        action="store_true",
        help="overwrite the notebooks with their executed versions (refresh committed ones)",
    )
    p.add_argument(
        "--check", action="store_true", help="only check the parameter file, run nothing"
    )
    add_json_flag(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..runner import check_params, load_params, run_notebooks

    if args.check:
        todo = check_params(load_params(args.params), args.notebooks, only=args.only)
        return emit(
            {"params": args.params, "notebooks": sorted(todo)},
            f"{args.params}: OK for {len(todo)} notebook(s): {', '.join(sorted(todo))}",
            args,
        )
    runs = run_notebooks(
        args.params,
        notebooks_dir=args.notebooks,
        output_dir=args.output,
        only=args.only,
        in_place=args.in_place,
        progress=lambda line: print(line, file=sys.stderr),
    )
    result = {
        "params": args.params,
        "notebooks": [
            {"name": r.name, "output": str(r.output), "seconds": round(r.seconds, 1)} for r in runs
        ],
    }
    text = "\n".join(f"{r.name}: {r.seconds:.1f} s -> {r.output}" for r in runs)
    return emit(result, text or "no notebooks run", args)
