"""``beatsync reproduce``: run the study's notebooks with papermill (:mod:`beatsync.runner`).

A notebook that fails is kept as ``<name>.failed.ipynb`` beside its destination; the
artefacts the notebooks write themselves (``results/<notebook>/``) are theirs.
"""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path

from . import COMMAND_HELP
from ._common import Outputs, add_output_flags, emit, feedback


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "reproduce",
        help=COMMAND_HELP["reproduce"],
        description="Execute every notebook (or --only some) with the parameters of a "
        "parameter file; refuse parameters a notebook does not declare. The executed "
        "notebooks replace the previous ones only when all of them ran.",
    )
    p.add_argument("--params", default="params/paper.yaml", help="parameter file (YAML)")
    p.add_argument("--notebooks", default="notebooks", help="folder of the notebooks")
    p.add_argument(
        "--output",
        default="results/notebooks",
        help="folder for the executed notebooks (created if missing)",
    )
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these notebooks")
    p.add_argument(
        "--in-place",
        action="store_true",
        help="overwrite the notebooks with their executed versions (refresh committed ones)",
    )
    p.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help="notebooks run at once, each in a process of its own (default: the number of "
        "CPUs, at most 4)",
    )
    p.add_argument(
        "--check", action="store_true", help="only check the parameter file, run nothing"
    )
    add_output_flags(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..errors import ParameterError
    from ..io import check_input_file
    from ..runner import check_params, default_jobs, load_params, planned_outputs, run_notebooks

    check_input_file(args.params, "parameter")
    if not Path(args.notebooks).is_dir():
        raise ParameterError(f"--notebooks {args.notebooks!r} is not a folder of notebooks")
    if args.check and args.in_place:
        raise ParameterError("--check runs nothing, so --in-place has nothing to overwrite")
    if args.jobs is not None and args.jobs < 1:
        raise ParameterError(f"--jobs {args.jobs}: run at least one notebook at a time")
    todo = check_params(load_params(args.params), args.notebooks, only=args.only)
    jobs = args.jobs if args.jobs is not None else default_jobs(len(todo))
    if args.check:
        return emit(
            {"params": args.params, "notebooks": sorted(todo)},
            f"{args.params}: OK for {len(todo)} notebook(s): {', '.join(sorted(todo))}",
            args,
        )
    fb = feedback(args)
    out_dir = Path(args.output)
    made = None
    if not args.in_place:
        if out_dir.exists() and not out_dir.is_dir():
            raise ParameterError(f"--output {args.output!r} is a file, not a folder")
        if not out_dir.exists():
            made = next((p for p in [out_dir, *out_dir.parents] if p.exists()), None)
            out_dir.mkdir(parents=True)
    try:
        with Outputs(inputs=[args.params]) as outs:
            for name, dest in planned_outputs(
                todo, output_dir=out_dir, in_place=args.in_place
            ).items():
                # in place, a notebook is both input and output: declared as output only
                outs.add(dest, option=f"notebook {name}" if name in todo else "manifest")
            runs = run_notebooks(
                args.params,
                notebooks_dir=args.notebooks,
                output_dir=out_dir,
                only=args.only,
                in_place=args.in_place,
                jobs=jobs,
                progress=fb.info,
                write_to=outs.path,
            )
    except BaseException:
        if made is not None:  # remove the folders this command created, if still empty
            for folder in [out_dir, *out_dir.parents]:
                if folder == made:
                    break
                with contextlib.suppress(OSError):
                    folder.rmdir()
        raise
    result = {
        "params": args.params,
        "notebooks": [
            {"name": r.name, "output": str(r.output), "seconds": round(r.seconds, 1)} for r in runs
        ],
    }
    if args.quiet and not args.json:
        return 0  # nothing but errors and warnings
    text = "\n".join(f"{r.name}: {r.seconds:.1f} s -> {r.output}" for r in runs)
    return emit(result, text or "no notebooks run", args)
