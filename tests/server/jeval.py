"""jeval.py - the JSON evaluator behind lib.sh's jget, kept running for the whole test script so
that each query costs no Python start-up. Reads lines "FILE<TAB>EXPR", evaluates the Python
expression EXPR with d = the JSON in FILE, and writes one line: strings bare, the rest as JSON,
or "ERROR: ..." (newlines escaped)."""
import json
import sys

for line in sys.stdin:
    path, _, expr = line.rstrip("\n").partition("\t")
    try:
        with open(path) as f:
            d = json.load(f)
        v = eval(expr)
        out = v if isinstance(v, str) else json.dumps(v)
    except Exception as e:  # the answer names the problem; the test compares and reports it
        out = "ERROR: %s: %s" % (type(e).__name__, e)
    sys.stdout.write(out.replace("\n", "\\n") + "\n")
    sys.stdout.flush()
