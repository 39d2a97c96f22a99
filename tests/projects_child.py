"""A writer of the projects store in a process of its own, for the fault tests.

    python tests/projects_child.py DATA_DIR PID USER OP TAG N SIZE STOP_AT STOP_POINT

Does ``N`` operations ``OP`` (``candidate``: add a candidate named ``TAG-i`` with
:func:`payload` bytes; ``view``: save a view ``TAG-i``; ``project``: create a project) and
prints ``ACK <i> <id>`` after each has returned (what the service acknowledged). In operation
number ``STOP_AT`` (1-based; 0: never) it prints ``AT <point>`` when it reaches the storage
checkpoint ``STOP_POINT`` and waits for a line on stdin: the parent kills it there (SIGKILL),
or lets it go on. Every other checkpoint of ``announce`` points (``ANNOUNCE`` environment
variable, comma-separated) is printed without waiting. No sleeps: the parent decides.
"""

from __future__ import annotations

import hashlib
import os
import sys

GROUPS = "oem:alice,bob;supplier_x:carol"


def payload(tag: str, i: int, size: int) -> bytes:
    """Deterministic bytes of candidate ``tag-i`` (distinct per tag and i)."""
    block = hashlib.sha256(f"{tag}-{i}".encode()).digest()
    return (block * (size // len(block) + 1))[:size]


def main(argv: list[str]) -> None:
    from app.projects import Projects, parse_groups
    from app.projects.storage import HOOKS

    data, pid, user, op, tag = argv[:5]
    n, size, stop_at = int(argv[5]), int(argv[6]), int(argv[7])
    stop_point = argv[8]
    announce = set(filter(None, os.environ.get("ANNOUNCE", "").split(",")))
    current = 0

    def checkpoint(point: str) -> None:
        if current == stop_at and point == stop_point:
            print("AT", point, flush=True)
            sys.stdin.readline()
        elif point in announce:
            print("AT", point, current, flush=True)

    HOOKS.checkpoint = checkpoint
    projects = Projects(data, parse_groups(GROUPS), scan=False)
    for i in range(1, n + 1):
        current = i
        name = f"{tag}-{i}"
        if op == "candidate":
            c = projects.add_candidate(
                user, pid, f"{name}.h5", payload(tag, i, size), {"name": name, "supplier": "X"}
            )
            print("ACK", i, c.id, flush=True)
        elif op == "view":
            vid = projects.save_view(user, pid, name, f"?view={name}")
            print("ACK", i, vid, flush=True)
        elif op == "project":
            info = projects.create_project(user, name, {"oem": None})
            print("ACK", i, info.id, flush=True)
        else:
            raise SystemExit(f"unknown operation {op!r}")
    print("DONE", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
