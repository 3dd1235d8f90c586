"""Band checks of the studies: each check prints its measured value, its band and the reason,
and the process exits 1 when any result leaves its band."""
import json
import sys


class Bands:
    def __init__(self, title):
        self.title = title
        self.failed = 0
        self.n = 0

    def check(self, ok, what, measured, band, reason):
        self.n += 1
        self.failed += not ok
        print("  %s %s: %s (band %s; %s)" % ("ok  " if ok else "FAIL", what, measured, band,
                                              reason))

    def finish(self):
        print("%s: %d checks, %d outside their band" % (self.title, self.n, self.failed))
        sys.exit(1 if self.failed else 0)


def load_cases(path):
    with open(path) as f:
        return {(c["triangles"], c["E_Pa"]): c for c in json.load(f)["cases"]}
