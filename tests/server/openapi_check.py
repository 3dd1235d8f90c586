#!/usr/bin/env python3
"""openapi_check.py - real responses of polydemd against schemas/openapi.yaml.

    python3 tests/server/openapi_check.py schemas/openapi.yaml CASES

CASES holds one recorded response a line: "NAME METHOD TEMPLATE STATUS HEADERS BODY", where
TEMPLATE is the documented path ("/v1/jobs/{id}/frames/{k}"), HEADERS and BODY files as curl -D and
-o write them. For each one: the status is one the operation documents (or one that the spec's
description allows any route: 403, 405, 414, 500), the Content-Type is a documented one, a JSON
body validates against the documented schema (every 4xx and 5xx against Error), and the
documented headers are present. Prints "ok   NAME" or "FAIL NAME: why" per case, then "done".
"""
import json
import sys

import jsonschema
import yaml

ANY_ROUTE = {"403", "405", "414", "500"}  # the spec's description: any route may answer these


def load_spec(path):
    return yaml.safe_load(open(path))


def to_json_schema(node):
    """OpenAPI 3.0 schema objects to JSON Schema: nullable becomes a union with null."""
    if isinstance(node, list):
        return [to_json_schema(x) for x in node]
    if not isinstance(node, dict):
        return node
    out = {}
    for k, v in node.items():
        if k in ("nullable", "example", "format"):
            continue
        if k == "$ref":
            out[k] = v.replace("#/components/schemas/", "#/definitions/")
            continue
        if k in ("properties", "definitions"):
            out[k] = {name: to_json_schema(s) for name, s in v.items()}
        else:
            out[k] = to_json_schema(v)
    if node.get("nullable"):
        return {"anyOf": [out, {"type": "null"}]}
    return out


def resolve(spec, node):
    while isinstance(node, dict) and "$ref" in node:
        cur = spec
        for part in node["$ref"].lstrip("#/").split("/"):
            cur = cur[part]
        node = cur
    return node


def headers_of(path):
    """The last response's headers (curl -D keeps every one of a redirect chain)."""
    status, hdrs = None, {}
    for line in open(path, encoding="latin-1"):
        line = line.rstrip("\r\n")
        if line.startswith("HTTP/"):
            status, hdrs = line.split()[1], {}
        elif ":" in line:
            k, v = line.split(":", 1)
            hdrs[k.strip().lower()] = v.strip()
    return status, hdrs


def check(spec, defs, name, method, template, status, hfile, bfile):
    item = spec["paths"].get(template)
    if item is None:
        return "no path %s in the spec" % template
    op = item.get("get" if method == "HEAD" else method.lower())  # GET routes answer HEAD
    got_status, hdrs = headers_of(hfile)
    if op is None and status == "405":  # a method the path does not serve
        if "allow" not in hdrs:
            return "405 without an Allow header"
        op = {"responses": {}}
    if op is None:
        return "no %s %s in the spec" % (method, template)
    if got_status != status:
        return "the headers say %s, the case %s" % (got_status, status)
    responses = op.get("responses", {})
    if status not in responses and status not in ANY_ROUTE:
        return "status %s is not documented (documented: %s)" % (status, sorted(responses))
    resp = resolve(spec, responses.get(status, {}))
    body = open(bfile, "rb").read()
    ctype = hdrs.get("content-type", "").split(";")[0].strip()
    content = resp.get("content")
    if status[0] in "45" and not content:
        content = {"application/json": {"schema": {"$ref": "#/components/schemas/Error"}}}
    if status in ("204", "304"):
        return "a body of %d bytes" % len(body) if body else None
    if method == "HEAD":
        return None
    if content:
        if ctype not in content:
            return "Content-Type '%s' is not documented (%s)" % (ctype, sorted(content))
        schema = content[ctype].get("schema")
        if ctype == "application/json" and schema:
            try:
                doc = json.loads(body)
            except ValueError as e:
                return "the body is not JSON: %s: %r" % (e, body[:80])
            js = to_json_schema(schema)
            js["definitions"] = defs
            errs = sorted(jsonschema.Draft7Validator(js).iter_errors(doc), key=str)
            if errs:
                e = errs[0]
                return "%d schema error(s); the first at /%s: %s" % (
                    len(errs), "/".join(str(p) for p in e.absolute_path), e.message[:300])
    for h in resp.get("headers", {}):
        if h.lower() not in hdrs and h != "Retry-After":
            return "header %s missing" % h
    if status[0] in "45" and ctype != "application/json":
        return "an error answered as '%s', not JSON" % ctype
    return None


def main():
    spec = load_spec(sys.argv[1])
    defs = {k: to_json_schema(v) for k, v in spec["components"]["schemas"].items()}
    for line in open(sys.argv[2]):
        f = line.split()
        if len(f) != 6:
            continue
        why = check(spec, defs, *f)
        print("ok   %s" % f[0] if why is None else "FAIL %s: %s" % (f[0], why))
    print("done")


if __name__ == "__main__":
    main()
