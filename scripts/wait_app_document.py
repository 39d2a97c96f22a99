"""Wait until a served dashboard has proved its app: ``/liveness?endpoint=/main`` says true.

Used by scripts/docker_proof.sh and scripts/compose_proof.sh once the container is healthy.
The endpoint answers 503 until the server has built a page of the app once after its port
opened (seconds on a busy machine): that is waited for (deadline 300 s), not a fixed time;
any other answer fails at once.

Usage: python scripts/wait_app_document.py PORT
"""

from __future__ import annotations

import sys
import time
import urllib.error
import urllib.request


def main(port: str, deadline_s: float = 300.0) -> None:
    url = f"http://127.0.0.1:{port}/liveness?endpoint=/main"
    end = time.monotonic() + deadline_s
    while True:
        try:
            with urllib.request.urlopen(url, timeout=120) as r:
                body = r.read().decode()
                assert r.status == 200 and "true" in body, body
            break
        except urllib.error.HTTPError as e:
            if e.code != 503 or time.monotonic() > end:
                raise
            time.sleep(0.5)
    print(f"    {url} -> {body}")


if __name__ == "__main__":
    main(sys.argv[1])
