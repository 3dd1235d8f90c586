#!/usr/bin/env python3
"""polydemd_load.py - polydemd under HTTP load while a job runs (issue 4's load check).

Starts build/polydemd on a free loopback port with a scratch data directory, then runs the same
job several times, alternately alone and while CLIENTS threads poll the status routes (the job,
the job list, /healthz, /v1/device, /metrics) over keep-alive connections, each at most RATE
requests per second (0: as fast as it can). Reports requests/s, latency, errors, and the job's
own wall time (the engine's wall_seconds), and the slowdown of loaded runs against lone ones.

  python3 bench/polydemd_load.py [--polydemd build/polydemd] [--scenario FILE] [--clients 4]
                                 [--rate 50] [--runs 2]

Exit status 1 when any request failed or the job slowed down by more than --max-slowdown (5 %).
Standard library only.
"""
import argparse
import http.client
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time


def request(conn, method, path, body=None):
    conn.request(method, path, body=body, headers={"Content-Type": "application/json"})
    r = conn.getresponse()
    return r.status, r.read()


def start(binary, data):
    log = open(os.path.join(data, "polydemd.log"), "w")
    p = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--data", data], stderr=log,
                         stdout=log)
    for _ in range(600):
        text = open(log.name).read()
        m = re.search(r"listening on http://127\.0\.0\.1:(\d+)", text)
        if m:
            port = int(m.group(1))
            break
        if p.poll() is not None:
            sys.exit("polydemd exited: " + text)
        time.sleep(0.1)
    else:
        sys.exit("polydemd did not start")
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    for _ in range(1200):  # the device self-test
        if request(conn, "GET", "/healthz")[0] == 200:
            return p, port
        time.sleep(0.1)
    sys.exit("polydemd never became healthy: " + open(log.name).read())


class Poller(threading.Thread):
    """Polls the status routes until told to stop; counts answers, errors and latencies."""

    def __init__(self, port, job, rate, stop):
        super().__init__(daemon=True)
        self.port, self.job, self.rate, self.stop = port, job, rate, stop
        self.ok = self.errors = 0
        self.lat = []

    def run(self):
        routes = ["/v1/jobs/" + self.job, "/v1/jobs?limit=20", "/healthz", "/v1/device",
                  "/metrics"]
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
        i = 0
        while not self.stop.is_set():
            t0 = time.monotonic()
            try:
                st, _ = request(conn, "GET", routes[i % len(routes)])
                good = st == 200
            except (OSError, http.client.HTTPException):
                good = False
                conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
            dt = time.monotonic() - t0
            self.lat.append(dt)
            if good:
                self.ok += 1
            else:
                self.errors += 1
            i += 1
            if self.rate > 0:
                time.sleep(max(0.0, 1.0 / self.rate - dt))


def run_job(port, scenario, clients, rate):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    st, body = request(conn, "POST", "/v1/jobs", scenario)
    if st != 201:
        sys.exit("submit: %d %s" % (st, body[:300]))
    job = json.loads(body)["id"]
    stop = threading.Event()
    pollers = [Poller(port, job, rate, stop) for _ in range(clients)]
    t0 = time.monotonic()
    for p in pollers:
        p.start()
    while True:
        j = json.loads(request(conn, "GET", "/v1/jobs/" + job)[1])
        if j["status"] in ("succeeded", "failed", "cancelled"):
            break
        time.sleep(0.2)
    stop.set()
    for p in pollers:
        p.join()
    span = time.monotonic() - t0
    if j["status"] != "succeeded":
        sys.exit("job %s: %s %s" % (job, j["status"], j["error"]))
    lat = sorted(x for p in pollers for x in p.lat)
    n = sum(p.ok for p in pollers)
    return {
        "wall": j["progress"]["wall_seconds"],
        "sps": j["progress"]["steps_per_second"],
        "requests": n,
        "errors": sum(p.errors for p in pollers),
        "rps": n / span if span > 0 else 0,
        "p50": 1e3 * lat[len(lat) // 2] if lat else 0,
        "p99": 1e3 * lat[min(len(lat) - 1, int(len(lat) * 0.99))] if lat else 0,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--polydemd", default="build/polydemd")
    ap.add_argument("--scenario", default="tests/server/long_job.json")
    ap.add_argument("--clients", type=int, default=4)
    ap.add_argument("--rate", type=float, default=50, help="requests/s per client; 0: unlimited")
    ap.add_argument("--runs", type=int, default=2, help="pairs of lone and loaded runs")
    ap.add_argument("--max-slowdown", type=float, default=5.0, help="percent")
    a = ap.parse_args()
    scenario = open(a.scenario, "rb").read()
    data = tempfile.mkdtemp(prefix="polydemd-load-")
    proc = None
    try:
        proc, port = start(a.polydemd, data)
        run_job(port, scenario, 0, 0)  # warm-up: kernels compiled, caches filled
        rows = []
        for _ in range(a.runs):
            rows.append(("alone", run_job(port, scenario, 0, 0)))
            rows.append(("loaded", run_job(port, scenario, a.clients, a.rate)))
        print("%-7s %9s %9s %9s %9s %7s %8s %8s" % ("run", "job s", "steps/s", "requests",
                                                   "req/s", "errors", "p50 ms", "p99 ms"))
        for kind, r in rows:
            print("%-7s %9.3f %9.0f %9d %9.0f %7d %8.2f %8.2f" % (
                kind, r["wall"], r["sps"], r["requests"], r["rps"], r["errors"], r["p50"],
                r["p99"]))
        alone = [r["wall"] for k, r in rows if k == "alone"]
        loaded = [r["wall"] for k, r in rows if k == "loaded"]
        slow = 100 * (sum(loaded) / len(loaded) / (sum(alone) / len(alone)) - 1)
        errors = sum(r["errors"] for _, r in rows)
        print("clients %d at %s req/s each: job slowdown %+.1f %% (limit %.0f %%), %d errors" % (
            a.clients, a.rate if a.rate > 0 else "unlimited", slow, a.max_slowdown, errors))
        return 0 if errors == 0 and slow <= a.max_slowdown else 1
    finally:
        if proc:
            proc.terminate()
            proc.wait(timeout=30)
        shutil.rmtree(data, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
