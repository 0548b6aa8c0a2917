"""The --workers and --dask options of the commands that fan runs out (springsim.runner)."""


def add_worker_arguments(parser) -> None:
    parser.add_argument("--workers", type=int, metavar="N",
                        help="local worker processes (default: every core)")
    parser.add_argument("--dask", metavar="ADDRESS",
                        help="run on the Dask cluster whose scheduler is at ADDRESS, for example "
                             "tcp://scheduler:8786 (default: $DASK_SCHEDULER_ADDRESS if set, "
                             "else local processes)")
