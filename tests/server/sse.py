"""sse.py URL SECONDS [JOB_ID]: reads a Server-Sent Events stream and prints one JSON line per
event ({"event": name, "data": decoded JSON}). Ends at the end of the stream (exit 0), when it
has seen a final status of JOB_ID (exit 0; for the all-jobs stream), or after SECONDS (exit 3).
The first line printed is "HTTP <status> <content-type>"."""
import http.client
import json
import sys
import time
import urllib.parse

FINAL = ("succeeded", "failed", "cancelled")


def main():
    url = urllib.parse.urlsplit(sys.argv[1])
    limit = float(sys.argv[2])
    job = sys.argv[3] if len(sys.argv) > 3 else None
    start = time.monotonic()
    conn = http.client.HTTPConnection(url.hostname, url.port, timeout=limit)
    path = url.path + ("?" + url.query if url.query else "")
    conn.request("GET", path, headers={"Accept": "text/event-stream"})
    resp = conn.getresponse()
    print("HTTP %d %s" % (resp.status, resp.getheader("Content-Type")), flush=True)
    event, data = "message", []
    while True:
        if time.monotonic() - start > limit:
            return 3
        try:
            line = resp.readline()
        except TimeoutError:
            return 3
        if not line:
            return 0
        line = line.decode("utf-8").rstrip("\r\n")
        if line.startswith(":"):
            continue
        if line.startswith("event:"):
            event = line[6:].strip()
        elif line.startswith("data:"):
            data.append(line[5:].strip())
        elif line == "" and data:
            payload = json.loads("\n".join(data))
            print(json.dumps({"event": event, "data": payload}), flush=True)
            if (job and event == "status" and payload.get("id") == job
                    and payload.get("status") in FINAL):
                return 0
            event, data = "message", []


if __name__ == "__main__":
    sys.exit(main())
