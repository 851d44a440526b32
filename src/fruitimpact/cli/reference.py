"""``fruitimpact paper`` and ``fruitimpact models``: the founding paper reproduced, and
what each damping law really produces."""

from __future__ import annotations

import math

from fruitimpact.cli.common import UsageError, _float_list, _library_call, dump_json


def _checked(check, *args):
    try:
        return check(*args)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def cmd_paper(args) -> int:
    from fruitimpact.impact.outputs import check_output_folder

    if args.figures:
        _checked(check_output_folder, args.figures, "--figures")
    from fruitimpact.reference.paper import format_paper_report, paper_report  # the engine: once the options hold

    report = paper_report()
    if args.figures:
        from fruitimpact.reference.paper import write_paper_figures

        report["figures"] = _library_call(write_paper_figures, args.figures)
    if args.json:
        print(dump_json(report))
    else:
        print(format_paper_report(report))
    return 0



def cmd_models(args) -> int:
    from fruitimpact.physics import DAMPING_LAWS

    for name in args.model or ():
        if name not in DAMPING_LAWS:
            raise UsageError(f"argument --model: model must be one of {', '.join(DAMPING_LAWS)}; got {name!r}")
    targets = _float_list("--targets", args.targets, 0.0, 1.0, True)
    velocities = _float_list("--velocities", args.velocities, 0.0, math.inf, False)
    from fruitimpact.impact.outputs import CSV_FORMAT, FIGURE_FORMATS, atomic_write, check_output

    if args.csv:
        _checked(check_output, args.csv, "--csv", CSV_FORMAT)
    if args.plot:
        _checked(check_output, args.plot, "--plot", FIGURE_FORMATS)
    # the engine and matplotlib only once every option holds (a usage error in 0.25 s, issue 15 item 4)
    from fruitimpact.reference.comparison import format_restitution_table, restitution_table

    table = restitution_table(args.model, targets, velocities)
    if args.csv:
        _library_call(atomic_write, args.csv, lambda tmp: table.to_csv(tmp, index=False), "--csv")
    if args.plot:
        from fruitimpact.plotting import restitution_figure, save_figure

        _library_call(save_figure, restitution_figure(table), args.plot, "--plot")
    if args.json:
        print(dump_json(table.to_dict(orient="records")))
    else:
        print("Restitution each law's published calibration really produces (Jonathan apple: M = 115 g, "
              "k_c = 0.835e6 N/m^1.5)\n")
        print(format_restitution_table(table))
        for what, path in (("table", args.csv), ("figure", args.plot)):
            if path:
                print(f"{what} written to {path}")
    return 0



def add_parsers(sub) -> None:
    pap = sub.add_parser("paper", help="reproduce the founding paper's Table 1 and worked example")
    pap.add_argument("--json", action="store_true", help="print everything as JSON")
    pap.add_argument("--figures", metavar="DIR", help="write the worked example's figures to DIR")
    pap.set_defaults(func=cmd_paper)

    mod = sub.add_parser("models", help="achieved vs requested restitution of every damping law",
                         description="For each damping law, the restitution its published calibration really "
                                     "produces against the one it was given.")
    mod.add_argument("--model", action="append", metavar="NAME", help="only this law (repeatable)")
    mod.add_argument("--targets", default="0.1,0.3,0.5,0.7,0.9", metavar="LIST",
                     help="requested restitution coefficients, comma-separated, each in (0, 1]")
    mod.add_argument("--velocities", default="0.5,1,3", metavar="LIST",
                     help="impact velocities, comma-separated, each > 0 [m/s]")
    mod.add_argument("--json", action="store_true", help="print the table as JSON records")
    mod.add_argument("--csv", metavar="FILE", help="write the table as CSV")
    mod.add_argument("--plot", metavar="FILE", help="write achieved vs requested e (PNG/SVG/PDF)")
    mod.set_defaults(func=cmd_models)
