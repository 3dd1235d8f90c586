#!/usr/bin/env python3
"""polydem_client - a small client for polydemd, standard library only.

As a library:

    from polydem_client import Client
    c = Client("http://127.0.0.1:8080", token=None)
    job = c.submit_file("examples/collision.json", tags=["demo"])
    job = c.wait(job["id"], progress=progress_printer())
    c.download(job["id"], "collision.h5")
    c.download(job["id"], "collision.h5.xmf", xmf=True)   # refers to collision.h5
    sweep_id, rows = c.sweep(load_scenario("examples/collision.json"),
                             [("/interactions/0/friction", [0.2, 0.3])])

As a command (python3 clients/python/polydem_client.py COMMAND --help for each):

    submit SCENARIO.json [--tag T] [--priority N] [--wait]   prints the job id
    wait JOB_ID...                                            progress on stderr until they end
    download JOB_ID [-o FILE] [--xmf]                         the HDF5 result (or its XDMF)
    sweep SCENARIO.json --set PTR=V1,V2 [--set ...] [--out FILE]   the same CSV as clients/sweep.sh
    cancel JOB_ID... | cancel --tag TAG                       cancel queued or running jobs

--server (default $POLYDEM_SERVER or http://127.0.0.1:8080) and --token (default $POLYDEM_TOKEN)
go before the command. Exit status: 0 success; 1 a job failed or was refused; 2 bad usage or
input; 3 the server cannot be reached, the connection is cut, or the server answers something
unexpected; 130 (143 for SIGTERM) interrupted.
"""

import argparse
import csv
import hashlib
import http.client
import io
import itertools
import json
import math
import os
import re
import signal
import sys
import time
import urllib.error
import urllib.parse
import urllib.request

DEFAULT_SERVER = "http://127.0.0.1:8080"
FINISHED = ("succeeded", "failed", "cancelled")
GONE = "deleted"  # a job that disappeared (404) while wait(..., missing_ok=True) waited for it
CSV_TAIL = ["status", "final_kinetic_energy_J", "peak_contacts", "peak_wall_force_N"]


class PolydemError(Exception):
    """An error answer from the server (status > 0) or no answer at all (status 0)."""

    def __init__(self, status, message, details=None):
        super().__init__(message)
        self.status = status
        self.message = message
        self.details = details or []
        self.retry_after = None

    def __str__(self):
        lines = [self.message if self.status == 0 else "HTTP %d: %s" % (self.status, self.message)]
        lines += ["  %s: %s" % (d.get("path", "?"), d.get("message", "")) for d in self.details]
        return "\n".join(lines)


# ---- JSON pointers (RFC 6901) -------------------------------------------------------------------

def pointer_tokens(pointer):
    if pointer == "":
        return []
    if not pointer.startswith("/"):
        raise ValueError("JSON pointer %r must start with '/'" % pointer)
    return [t.replace("~1", "/").replace("~0", "~") for t in pointer[1:].split("/")]


def pointer_set(doc, pointer, value):
    """Returns a copy of doc with value at pointer; containers on the way must exist (the last
    object member may be new). Raises ValueError naming what does not fit."""
    doc = json.loads(json.dumps(doc))
    toks = pointer_tokens(pointer)
    if not toks:
        return value
    cur = doc
    for depth, t in enumerate(toks):
        last = depth == len(toks) - 1
        where = "/" + "/".join(toks[:depth]) if depth else "the document"
        if isinstance(cur, list):
            if not t.isdigit() or (len(t) > 1 and t[0] == "0"):
                raise ValueError("%s is an array: %r is not an index" % (where, t))
            i = int(t)
            if i >= len(cur):
                raise ValueError("%s has %d elements, no index %d" % (where, len(cur), i))
        elif isinstance(cur, dict):
            i = t
            if not last and i not in cur:
                raise ValueError("%s has no member %r" % (where, t))
        else:
            raise ValueError("%s is a %s, not a container" % (where, type(cur).__name__))
        if last:
            cur[i] = value
        else:
            cur = cur[i]
    return doc


def split_values(text):
    """Splits 'V1,V2,...' at commas outside brackets, braces and strings; each value is JSON
    when it parses as JSON, else text. Returns [(text, value)]."""
    parts, cur, depth, in_str, esc = [], "", 0, False, False
    for ch in text:
        if in_str:
            esc = (not esc) and ch == "\\"
            if ch == '"' and not esc:
                in_str = False
            cur += ch
            continue
        if ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        cur += ch
    parts.append(cur)
    out = []
    for p in parts:
        p = p.strip()
        if not p:
            raise ValueError("empty value")
        try:
            out.append((p, json.loads(p)))
        except ValueError:
            out.append((p, p))
    return out


def parse_set(spec):
    """'POINTER=V1,V2' -> (pointer, [(text, value)]); ValueError with the expected form."""
    form = "expected POINTER=V1,V2,... with POINTER starting with '/', e.g. /interactions/0/friction=0.2,0.3"
    if not spec.startswith("/") or "=" not in spec:
        raise ValueError("--set %r: %s" % (spec, form))
    pointer, values = spec.split("=", 1)
    try:
        return pointer, split_values(values)
    except ValueError as e:
        raise ValueError("--set %r: %s; %s" % (spec, e, form)) from None


# ---- /stats summaries ---------------------------------------------------------------------------

def stats_columns(stats):
    """The /stats answer as columns: {time: [...], kinetic_energy: [...], contacts: [...],
    wall_force: {name: [[fx, fy, fz], ...]}}; rows ([{time, ...}]) are turned into columns."""
    if isinstance(stats, dict) and isinstance(stats.get("stats"), (dict, list)):
        stats = stats["stats"]
    if isinstance(stats, list):
        cols = {"time": [], "kinetic_energy": [], "contacts": [], "wall_force": {}}
        for r in stats:
            for k in ("time", "kinetic_energy", "contacts"):
                cols[k].append(r.get(k))
            for name, f in (r.get("wall_force") or {}).items():
                cols["wall_force"].setdefault(name, []).append(f)
        return cols
    return stats if isinstance(stats, dict) else {}


def summarize(stats):
    """(final kinetic energy [J], peak contacts, peak |wall force| [N]); None where absent."""
    c = stats_columns(stats)
    ke = c.get("kinetic_energy") or []
    contacts = [x for x in (c.get("contacts") or []) if x is not None]
    forces = [math.sqrt(sum(x * x for x in f)) for series in (c.get("wall_force") or {}).values()
              for f in series if f]
    return (ke[-1] if ke else None, max(contacts) if contacts else None,
            max(forces) if forces else None)


# ---- the client ---------------------------------------------------------------------------------

class Client:
    def __init__(self, server=None, token=None, timeout=60.0):
        self.server = (server or os.environ.get("POLYDEM_SERVER") or DEFAULT_SERVER).rstrip("/")
        if not self.server.startswith(("http://", "https://")):
            raise ValueError("server %r: expected http://HOST:PORT or https://..." % self.server)
        self.token = token if token is not None else os.environ.get("POLYDEM_TOKEN") or None
        self.timeout = timeout

    def _open(self, method, path, body=None, headers=None):
        h = dict(headers or {})
        if self.token:
            h["Authorization"] = "Bearer " + self.token
        if body is not None and not isinstance(body, bytes):
            body = json.dumps(body).encode()
            h.setdefault("Content-Type", "application/json")
        req = urllib.request.Request(self.server + path, data=body, method=method, headers=h)
        try:
            return urllib.request.urlopen(req, timeout=self.timeout)
        except urllib.error.HTTPError as e:
            raise self._error(e) from None
        except (urllib.error.URLError, OSError) as e:
            reason = getattr(e, "reason", e)
            raise PolydemError(0, "cannot reach %s: %s" % (self.server, reason)) from None

    @staticmethod
    def _error(e):
        raw = e.read()
        try:
            err = json.loads(raw)["error"]
            pe = PolydemError(e.code, err.get("message", ""), err.get("details"))
        except (ValueError, KeyError, TypeError, AttributeError):
            pe = PolydemError(e.code, raw.decode("utf-8", "replace")[:300] or e.reason)
        pe.retry_after = e.headers.get("Retry-After")
        return pe

    def request(self, method, path, body=None, headers=None):
        """The decoded JSON answer (None for an empty one); PolydemError otherwise."""
        with self._open(method, path, body, headers) as r:
            try:
                data = r.read()
            except (OSError, http.client.HTTPException) as e:
                raise PolydemError(0, "%s %s: the connection was cut: %s" % (method, path, e)) from None
            if not data.strip():
                return None
            try:
                return json.loads(data)
            except ValueError:
                raise PolydemError(r.status, "%s %s: expected JSON, got %s: %s" % (
                    method, path, r.headers.get("Content-Type") or "no Content-Type",
                    data[:200].decode("utf-8", "replace"))) from None

    # jobs
    def submit(self, scenario, tags=None, priority=0, idempotency_key=None, queue_wait=600):
        """Submits a scenario (a dict); returns the job. A full queue (429) is waited out, up to
        queue_wait seconds, as its Retry-After says."""
        body = {"scenario": scenario, "tags": list(tags or []), "priority": priority}
        key = idempotency_key or hashlib.sha256(json.dumps(body, sort_keys=True).encode()
                                                + str(time.time()).encode()).hexdigest()[:32]
        deadline = time.monotonic() + queue_wait
        tries = 0
        while True:
            try:
                return self.request("POST", "/v1/jobs", body, {"Idempotency-Key": key})
            except PolydemError as e:
                tries += 1
                if e.status == 429 and time.monotonic() < deadline:
                    time.sleep(float(e.retry_after or 5))
                elif e.status == 0 and tries < 3:  # the key makes the retry safe
                    time.sleep(1)
                else:
                    raise

    def upload_meshes(self, scenario, base_dir, uploaded=None):
        """Replaces mesh file paths (shapes and walls) with the ids of uploaded meshes: the
        daemon cannot read the client's files. uploaded ({path: id}) remembers uploads across
        calls. Returns a new scenario."""
        sc = json.loads(json.dumps(scenario))
        uploaded = {} if uploaded is None else uploaded
        holders = list((sc.get("shapes") or {}).values()) + list(sc.get("walls") or [])
        for h in holders:
            path = h.get("mesh") if isinstance(h, dict) else None
            if isinstance(path, str) and not path.startswith("sha256:"):
                full = os.path.join(base_dir, path)
                if full not in uploaded:
                    try:
                        with open(full, "rb") as f:
                            data = f.read()
                    except OSError as e:
                        raise ValueError("mesh file %r: %s" % (full, e.strerror)) from None
                    uploaded[full] = self.request("POST", "/v1/meshes", data,
                                                  {"Content-Type": "application/octet-stream"})["id"]
                h["mesh"] = uploaded[full]
        return sc

    def submit_file(self, path, **kw):
        return self.submit(self.upload_meshes(load_scenario(path), os.path.dirname(path)), **kw)

    def job(self, job_id):
        return self.request("GET", "/v1/jobs/" + urllib.parse.quote(job_id, safe=""))

    def jobs(self, status=None, tag=None, limit=None):
        q = {k: v for k, v in (("status", status), ("tag", tag), ("limit", limit)) if v}
        r = self.request("GET", "/v1/jobs" + ("?" + urllib.parse.urlencode(q) if q else ""))
        return r.get("jobs", []) if isinstance(r, dict) else r

    def cancel(self, job_id):
        return self.request("POST", "/v1/jobs/%s/cancel" % urllib.parse.quote(job_id, safe=""))

    def delete(self, job_id):
        return self.request("DELETE", "/v1/jobs/" + urllib.parse.quote(job_id, safe=""))

    def stats(self, job_id):
        return self.request("GET", "/v1/jobs/%s/stats" % urllib.parse.quote(job_id, safe=""))

    def validate(self, scenario):
        return self.request("POST", "/v1/scenarios/validate", scenario)

    def wait(self, job_ids, poll=1.0, timeout=None, progress=None, lost_after=30.0,
             missing_ok=False):
        """Polls until every job has finished; returns {id: job}. progress(jobs) is called after
        every poll. TimeoutError after timeout seconds; PolydemError when the server has not
        answered for lost_after seconds, or for a job it does not know (404) unless missing_ok:
        then that job counts as finished with status "deleted"."""
        single = isinstance(job_ids, str)
        ids = [job_ids] if single else list(job_ids)
        jobs = {}
        done = FINISHED + (GONE,)
        start = last_ok = time.monotonic()
        while True:
            for i in ids:
                if i in jobs and jobs[i].get("status") in done:
                    continue
                try:
                    jobs[i] = self.job(i)
                    last_ok = time.monotonic()
                except PolydemError as e:  # a job not seen yet, or a long silence, ends the wait
                    if e.status == 404 and missing_ok:
                        jobs[i] = {"id": i, "status": GONE, "error": "gone from the server (deleted?)"}
                        continue
                    if e.status != 0 or i not in jobs or time.monotonic() - last_ok > lost_after:
                        raise
            if progress:
                progress(jobs)
            if all(jobs.get(i, {}).get("status") in done for i in ids):
                return jobs[ids[0]] if single else jobs
            if timeout is not None and time.monotonic() - start > timeout:
                raise TimeoutError("jobs still unfinished after %g s" % timeout)
            time.sleep(poll)

    def download(self, job_id, path, xmf=False, chunk=1 << 20, h5_name=None):
        """Streams the result (or its XDMF) to path through path + '.part'. A partial download
        is resumed with a Range request only when the file is still the one it started with: its
        ETag, kept in path + '.part.etag', goes along as If-Range, and a whole file in answer
        (the result changed) starts over. A transfer cut short keeps the .part and raises
        PolydemError (status 0); run it again to resume. The XDMF's references to the HDF5 file
        are rewritten to h5_name (default: path less '.xmf' when path ends in '.h5.xmf'; else
        they stay '<job id>.h5', the name download gives the result by default). Returns the
        number of bytes in the file."""
        route = "/v1/jobs/%s/result%s" % (urllib.parse.quote(job_id, safe=""), ".xmf" if xmf else "")
        part = path + ".part"
        tag_file = part + ".etag"
        have = os.path.getsize(part) if os.path.isfile(part) else 0
        etag = None
        if have:
            try:
                with open(tag_file, encoding="utf-8") as f:
                    etag = f.read().strip() or None
            except OSError:
                pass  # a .part of unknown origin: start over rather than glue two files
        headers = {"Range": "bytes=%d-" % have, "If-Range": etag} if etag else {}
        try:
            r = self._open("GET", route, headers=headers)
        except PolydemError as e:
            if e.status != 416 or not headers:
                raise
            r = self._open("GET", route)
        with r:
            ctype = r.headers.get("Content-Type") or ""
            if ctype.startswith("text/html"):
                raise PolydemError(r.status, "GET %s: expected the %s, got a web page (%s)" % (
                    route, "XDMF file" if xmf else "HDF5 result", ctype))
            if r.status == 206:
                m = re.match(r"bytes (\d+)-(\d+)/(\d+)$", (r.headers.get("Content-Range") or "").strip())
                if not m or int(m.group(1)) != have:
                    raise PolydemError(206, "GET %s: asked for bytes from %d, got Content-Range %r" % (
                        route, have, r.headers.get("Content-Range")))
                total = int(m.group(3))
            else:
                have = 0
                length = r.headers.get("Content-Length") or ""
                total = int(length) if length.isdigit() else None
                if r.headers.get("ETag"):
                    with open(tag_file, "w", encoding="utf-8") as f:
                        f.write(r.headers["ETag"] + "\n")
                elif os.path.exists(tag_file):
                    os.remove(tag_file)
            got, cut = have, None
            with open(part, "ab" if r.status == 206 else "wb") as f:
                while True:
                    try:
                        b = r.read(chunk)
                    except (OSError, http.client.HTTPException) as e:
                        cut = e
                        break
                    if not b:
                        break
                    f.write(b)
                    got += len(b)
        if cut is not None or (total is not None and got != total):
            raise PolydemError(0, "GET %s: the transfer stopped after %d of %s bytes%s; %s is kept: "
                               "run the download again to resume" % (
                                   route, got, total if total is not None else "?",
                                   " (%s)" % cut if cut is not None else "", part))
        if xmf:
            if h5_name is None and path.endswith(".h5.xmf"):
                h5_name = os.path.basename(path[:-4])
            if h5_name:
                rewrite_xmf_h5(part, h5_name)
        os.replace(part, path)
        if os.path.exists(tag_file):
            os.remove(tag_file)
        return os.path.getsize(path)

    def sweep(self, scenario, sets, tags=None, priority=0, poll=1.0, timeout=None, progress=None,
              log=None, base_dir=None):
        """Runs the grid of sets ([(pointer, [(text, value)])]; plain values are accepted too):
        returns (sweep_id, rows), each row [job_id, texts..., status, final KE, peak contacts,
        peak wall force]. Before anything is submitted, every pointer must fit the scenario
        (ValueError) and some grid point must pass POST /v1/scenarios/validate (else the first
        point's PolydemError, status 422): a misspelled member would only give a grid of refusals.
        Refused jobs get status 'rejected', jobs deleted while it waits 'deleted'; log(message)
        reports the sweep id and failures. With base_dir, mesh file paths (relative to it) are
        uploaded after the grid's values are put in, so a mesh path can be swept. On
        KeyboardInterrupt (Ctrl-C) it raises SweepInterrupted with the rows so far; unfinished
        jobs keep running."""
        log = log or (lambda m: None)
        sets = [(p, [v if isinstance(v, tuple) else (json.dumps(v), v) for v in vals])
                for p, vals in sets]
        for p, vals in sets:  # every pointer must fit before anything is submitted
            pointer_set(scenario, p, vals[0][1])
        sweep_id = "sweep-%s-%s" % (time.strftime("%Y%m%d-%H%M%S"), os.urandom(3).hex())
        grid = list(itertools.product(*[vals for _, vals in sets]))
        base = str(scenario.get("name", "scenario"))[:52]
        uploaded = {}

        def point(i):
            sc = scenario
            for (p, _), (_, v) in zip(sets, grid[i]):
                sc = pointer_set(sc, p, v)
            if base_dir is not None:
                sc = self.upload_meshes(sc, base_dir, uploaded)
            sc["name"] = "%s-%d" % (base, i)
            return sc

        def describe(i):
            return " ".join("%s=%s" % (p, t) for (p, _), (t, _) in zip(sets, grid[i]))

        first_error = None
        for i in range(len(grid)):  # the first point, and the others only while none is valid
            try:
                self.validate(point(i))
                break
            except PolydemError as e:
                if e.status != 422:
                    raise
                first_error = first_error or e
        else:
            first_error.message = "no grid point is valid, e.g. %s: %s" % (describe(0), first_error.message)
            raise first_error
        log("%s: submitting %d job%s to %s" % (sweep_id, len(grid), "" if len(grid) == 1 else "s",
                                               self.server))
        entries = [["", [t for t, _ in combo], "unsubmitted"] for combo in grid]
        latest = {}

        def seen(jobs):
            latest.update(jobs)
            if progress:
                progress(jobs)

        timed_out = interrupted = False
        try:
            for i in range(len(grid)):
                try:
                    job = self.submit(point(i), [sweep_id] + list(tags or []), priority,
                                      idempotency_key="%s-%d" % (sweep_id, i))
                    entries[i][0], entries[i][2] = job["id"], job.get("status", "queued")
                except PolydemError as e:
                    if e.status in (0, 401, 403):
                        raise
                    log("job %d (%s) refused: %s" % (i, describe(i), e))
                    entries[i][2] = "rejected"
            ids = [e[0] for e in entries if e[0]]
            try:
                if ids:
                    self.wait(ids, poll=poll, timeout=timeout, progress=seen, missing_ok=True)
            except TimeoutError as e:
                log(str(e))
                timed_out = True
        except KeyboardInterrupt as e:
            interrupted = e
        if interrupted and any(entry[2] == "unsubmitted" for entry in entries):
            # Interrupted while a submission's answer was on its way: the server may hold the job
            # whose id this sweep never read. Found by its tag and name, it is listed (and can be
            # cancelled) instead of running on as an "unsubmitted" point.
            try:
                for job in self.jobs(tag=sweep_id, limit=1000):
                    for i, entry in enumerate(entries):
                        if entry[2] == "unsubmitted" and job.get("name") == "%s-%d" % (base, i):
                            entry[0], entry[2] = job["id"], job.get("status", "queued")
                            latest[job["id"]] = job
            except (PolydemError, KeyboardInterrupt):
                pass
        rows = []
        for entry in entries:
            job_id, texts, status = entry
            ke = contacts = force = None
            job = latest.get(job_id) if job_id else None
            if job:
                status = entry[2] = job.get("status", "?")
                if status in ("failed", "cancelled", GONE):
                    log(unfinished(job))
                if status == "succeeded":
                    try:
                        ke, contacts, force = summarize(self.stats(job_id))
                    except PolydemError as e:
                        log("job %s: no usable /stats: %s" % (job_id, e))
            rows.append([job_id] + texts + [status, ke, contacts, force])
        self.last_sweep_timed_out = timed_out
        if interrupted:
            raise SweepInterrupted(sweep_id, rows, getattr(interrupted, "signum", signal.SIGINT))
        return sweep_id, rows


class SweepInterrupted(KeyboardInterrupt):
    """Client.sweep stopped by Ctrl-C (or SIGTERM through the command): .sweep_id, .rows (as
    sweep returns them; unfinished jobs with their last status, grid points not yet submitted
    'unsubmitted'), .signum."""

    def __init__(self, sweep_id, rows, signum=signal.SIGINT):
        super().__init__("sweep %s interrupted" % sweep_id)
        self.sweep_id, self.rows, self.signum = sweep_id, rows, signum


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised by the command's handler so that it ends like Ctrl-C."""
    signum = signal.SIGTERM


def rewrite_xmf_h5(path, h5_name):
    """Points every HDF DataItem of the XDMF file at path to the HDF5 file h5_name (the server
    writes its own name for it, '<job id>.h5')."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    name = h5_name.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    text = re.sub(r'(<DataItem\b[^>]*\bFormat="HDF"[^>]*>\s*)[^<]*?(?=:/)',
                  lambda m: m.group(1) + name, text)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def unfinished(job):
    """One line on a job that did not succeed: its status, its error, and whether the frames it
    wrote before it stopped can still be downloaded (result_available; the file's root attribute
    status then says "cancelled", "diverged" or "failed")."""
    text = "job %s %s" % (job.get("id"), job.get("status"))
    if job.get("error"):
        text += ": %s" % job["error"]
    if job.get("result_available") and job.get("status") in ("failed", "cancelled"):
        text += "; the frames it wrote before it stopped can be downloaded (download %s)" % job.get("id")
    return text


def load_scenario(path):
    try:
        with open(path, encoding="utf-8") as f:
            sc = json.load(f)
    except OSError as e:
        raise ValueError("cannot read scenario file %r: %s" % (path, e.strerror)) from None
    except ValueError as e:
        raise ValueError("%s: not valid JSON: %s" % (path, e)) from None
    if not isinstance(sc, dict):
        raise ValueError("%s: a scenario is a JSON object" % path)
    return sc


def write_csv(f, pointers, rows):
    w = csv.writer(f, lineterminator="\n")
    w.writerow(["job_id"] + list(pointers) + CSV_TAIL)
    for r in rows:
        w.writerow(["" if x is None else repr(x) if isinstance(x, float) else x for x in r])


# ---- command line -------------------------------------------------------------------------------

def progress_printer(stream=sys.stderr, every=5.0):
    """A wait() progress callback: a line when a status changes, else one every `every` s."""
    last = [None, 0.0]

    def show(jobs):
        parts = []
        for i, j in sorted(jobs.items()):
            p = j.get("progress") or {}
            s = "%s %s" % (i, j.get("status"))
            if j.get("status") == "running":
                s += " %.0f%%" % (100 * (p.get("fraction") or 0))
                if p.get("sim_time") is not None:
                    s += " t=%.4g s" % p["sim_time"]
                if p.get("steps_per_second"):
                    s += " %.0f steps/s" % p["steps_per_second"]
                if p.get("eta_seconds") is not None:
                    s += " ETA %.0f s" % p["eta_seconds"]
            parts.append(s)
        statuses = sorted((i, j.get("status")) for i, j in jobs.items())
        if parts and (statuses != last[0] or time.monotonic() - last[1] >= every):
            print("polydem: " + "; ".join(parts), file=stream, flush=True)
            last[0], last[1] = statuses, time.monotonic()
    return show


def writable(path):
    """None when a file can be written at path, else why not."""
    if path.endswith(("/", os.sep)) or os.path.isdir(path):
        return "is a directory; give a file name"
    folder = os.path.dirname(path) or "."
    if not os.path.isdir(folder):
        return "no such directory %r" % folder
    if os.path.exists(path) and not os.access(path, os.W_OK):
        return "not writable"
    if not os.path.exists(path) and not os.access(folder, os.W_OK | os.X_OK):
        return "cannot create files in %r" % folder
    return None


def exit_status(e):
    """The command's exit status for a PolydemError: 3 no answer, a refused token, a server
    error or an answer that makes no sense (a 2xx this client cannot use); else 1."""
    return 3 if e.status in (0, 401, 403) or e.status >= 500 or 200 <= e.status < 300 else 1


def cancel_jobs(c, ids, tag=None, log=None):
    """Cancels the jobs ids, or with tag every queued or running job carrying it; returns
    (cancelled ids, [(id, PolydemError)] for those that could not be)."""
    ids = list(ids)
    if tag:
        for status in ("queued", "running"):
            after = None
            while True:
                q = {"tag": tag, "status": status, "limit": 1000}
                if after:
                    q["after"] = after
                page = c.request("GET", "/v1/jobs?" + urllib.parse.urlencode(q)) or {}
                ids += [j["id"] for j in page.get("jobs", [])]
                after = page.get("next")
                if not after:
                    break
    done, refused = [], []
    for i in ids:
        try:
            c.cancel(i)
            done.append(i)
        except PolydemError as e:
            if e.status in (0, 401, 403):
                raise
            refused.append((i, e))
    return done, refused


def main(argv=None):
    ap = argparse.ArgumentParser(prog="polydem_client.py", description="Client for polydemd.")
    ap.add_argument("--server", help="polydemd address (default $POLYDEM_SERVER or %s)" % DEFAULT_SERVER)
    ap.add_argument("--token", help="bearer token (default $POLYDEM_TOKEN)")
    ap.add_argument("--timeout", type=float, default=None,
                    help="seconds to wait for jobs (wait, submit --wait, sweep; default: no limit)")
    sub = ap.add_subparsers(dest="cmd", metavar="COMMAND")
    sub.required = True
    p = sub.add_parser("submit", help="submit a scenario file; prints the job id")
    p.add_argument("scenario")
    p.add_argument("--tag", action="append", default=[])
    p.add_argument("--priority", type=int, default=0)
    p.add_argument("--idempotency-key")
    p.add_argument("--wait", action="store_true", help="wait for the job, progress on stderr")
    p = sub.add_parser("wait", help="wait for jobs to finish, progress on stderr")
    p.add_argument("job_id", nargs="+")
    p.add_argument("--poll", type=float, default=1.0)
    p = sub.add_parser("download", help="download a job's HDF5 result (or XDMF)")
    p.add_argument("job_id")
    p.add_argument("-o", "--output", help="file name (default JOB_ID.h5, or .xmf); an XDMF saved "
                   "as NAME.h5.xmf refers to NAME.h5")
    p.add_argument("--xmf", action="store_true", help="the XDMF descriptor instead")
    p = sub.add_parser("sweep", help="run a parameter grid; writes a CSV")
    p.add_argument("scenario")
    p.add_argument("--set", action="append", default=[], metavar="PTR=V1,V2",
                   help="JSON pointer and its values (repeat for a grid)")
    p.add_argument("--out", help="CSV file (default standard output)")
    p.add_argument("--tag", action="append", default=[])
    p.add_argument("--priority", type=int, default=0)
    p.add_argument("--poll", type=float, default=1.0)
    p = sub.add_parser("cancel", help="cancel queued or running jobs (by id, or every one with a tag)")
    p.add_argument("job_id", nargs="*")
    p.add_argument("--tag", help="every queued or running job with this tag (e.g. a sweep id)")
    a = ap.parse_args(argv)

    def fail(code, msg):
        print("polydem_client: " + msg, file=sys.stderr)
        return code

    def on_term(signum, frame):
        raise Terminated()

    try:
        c = Client(a.server, a.token)
    except ValueError as e:
        return fail(2, "--server: %s" % e)
    signal.signal(signal.SIGTERM, on_term)
    try:
        if a.cmd == "submit":
            job = c.submit_file(a.scenario, tags=a.tag, priority=a.priority,
                                idempotency_key=a.idempotency_key)
            print(job["id"], flush=True)
            if not a.wait:
                return 0
            job = c.wait(job["id"], timeout=a.timeout, progress=progress_printer())
            if job.get("status") != "succeeded":
                return fail(1, unfinished(job))
            return 0
        if a.cmd == "wait":
            jobs = c.wait(a.job_id, poll=a.poll, timeout=a.timeout, progress=progress_printer())
            bad = [j for j in jobs.values() if j.get("status") != "succeeded"]
            for j in bad:
                fail(1, unfinished(j))
            return 1 if bad else 0
        if a.cmd == "download":
            out = a.output or a.job_id + (".xmf" if a.xmf else ".h5")
            why = writable(out) or writable(out + ".part")
            if why:
                return fail(2, "-o %r: %s" % (out, why))
            n = c.download(a.job_id, out, xmf=a.xmf)
            print("polydem_client: wrote %s (%d bytes)" % (out, n), file=sys.stderr)
            return 0
        if a.cmd == "cancel":
            if not a.job_id and not a.tag:
                return fail(2, "cancel: give job ids or --tag TAG")
            done, refused = cancel_jobs(c, a.job_id, a.tag)
            for i, e in refused:
                fail(1, "job %s: %s" % (i, e))
            print("polydem_client: cancelled %d job%s" % (len(done), "" if len(done) == 1 else "s"),
                  file=sys.stderr)
            return 1 if refused else 0
        if a.cmd == "sweep":
            if not a.set:
                return fail(2, "sweep: no --set given: nothing to sweep")
            if a.poll <= 0:
                return fail(2, "--poll %g: expected seconds > 0" % a.poll)
            sets = [parse_set(s) for s in a.set]
            scenario = load_scenario(a.scenario)
            for p, vals in sets:
                try:
                    pointer_set(scenario, p, vals[0][1])
                except ValueError as e:
                    return fail(2, "--set %r: %r does not fit %s: %s" % (p + "=...", p, a.scenario, e))
            why = a.out and writable(a.out)
            if why:  # before anything runs: a sweep whose CSV cannot be written is wasted
                return fail(2, "--out %r: %s" % (a.out, why))
            log = lambda m: print("polydem_client: " + m, file=sys.stderr)  # noqa: E731
            stopped = None
            try:
                sweep_id, rows = c.sweep(scenario, sets, tags=a.tag, priority=a.priority, poll=a.poll,
                                         timeout=a.timeout, progress=progress_printer(), log=log,
                                         base_dir=os.path.dirname(a.scenario))
            except SweepInterrupted as e:
                stopped, sweep_id, rows = e, e.sweep_id, e.rows
            except PolydemError as e:
                if e.status != 422:
                    raise
                return fail(2, "%s: nothing submitted\n%s" % (a.scenario, e))
            buf = io.StringIO()
            write_csv(buf, [p for p, _ in sets], rows)
            if a.out:
                try:
                    with open(a.out, "w", encoding="utf-8") as f:
                        f.write(buf.getvalue())
                except OSError as e:
                    return fail(2, "--out %r: %s" % (a.out, e.strerror))
                log("%s: wrote %s (%d rows)" % (sweep_id, a.out, len(rows)))
            else:
                sys.stdout.write(buf.getvalue())
                sys.stdout.flush()
            left = [r[0] for r in rows if r[0] and r[-4] in ("queued", "running")]
            if stopped or left:
                log("%s: %s; %d job%s still queued or running (they go on; the dashboard shows "
                    "them at %s/index.html?tag=%s)" % (
                        sweep_id, "interrupted" if stopped else "stopped waiting", len(left),
                        "" if len(left) == 1 else "s", c.server, sweep_id))
                token = ""
                if c.token:
                    token = "" if c.token == os.environ.get("POLYDEM_TOKEN") else " --token TOKEN"
                log("to cancel them: python3 %s%s%s cancel --tag %s" % (
                    sys.argv[0] if sys.argv[0].endswith(".py") else "clients/python/polydem_client.py",
                    " --server " + c.server if c.server != DEFAULT_SERVER else "", token, sweep_id))
            if stopped:
                return 128 + int(stopped.signum)
            ok = all(r[-4] == "succeeded" for r in rows) and not c.last_sweep_timed_out
            return 0 if ok else 1
    except ValueError as e:
        return fail(2, str(e))
    except TimeoutError as e:
        return fail(1, str(e))
    except PolydemError as e:
        return fail(exit_status(e), str(e))
    except OSError as e:
        return fail(2, "%s: %s" % (e.filename or "", e.strerror or e))
    except KeyboardInterrupt as e:
        return fail(128 + int(getattr(e, "signum", signal.SIGINT)), "interrupted")
    return 2


if __name__ == "__main__":
    sys.exit(main())
