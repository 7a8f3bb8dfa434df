"""Schemathesis hooks of scripts/schemathesis: send NDJSON batch bodies (one JSON item a line)."""
import json

import schemathesis


@schemathesis.serializer("application/x-ndjson")
def ndjson(ctx, value):
    if isinstance(value, bytes):
        return {"data": value}
    if isinstance(value, str):
        return {"data": value.encode("utf-8", "surrogatepass")}
    items = value if isinstance(value, list) else [value]
    return {"data": b"".join(json.dumps(v).encode() + b"\n" for v in items)}
