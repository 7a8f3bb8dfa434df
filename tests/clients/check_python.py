"""Calls every endpoint through the Python client generated from openapi/openapi.json.

Usage: check_python.py PACKAGE_DIR BASE_URL. PACKAGE_DIR is the generated package (imported
under its directory name); BASE_URL a running server. Fails (exit 1) when a generated endpoint
function is missing or extra against the document's operations, when an answer is not a 200
parsed into its typed model, when a parsed model does not give back the JSON the server sent
(a field the document does not know), or when an invalid request is not a typed 422 problem
naming the field.
"""

import importlib
import json
import pathlib
import sys

package_dir = pathlib.Path(sys.argv[1])
base_url = sys.argv[2]
document = json.loads(pathlib.Path(sys.argv[3]).read_text())
sys.path.insert(0, str(package_dir.parent))
pkg = package_dir.name


def mod(name):
    return importlib.import_module(f"{pkg}.{name}")


models = mod("models")
client = mod("client").Client(base_url=base_url, timeout=60.0, raise_on_unexpected_status=True)
failures = []

# The generated endpoint functions are the document's operations, no more, no fewer.
operations = {
    op["operationId"]
    for item in document["paths"].values()
    for op in item.values()
    if isinstance(op, dict) and "operationId" in op
}
generated = {p.stem for p in package_dir.glob("api/*/*.py") if p.stem != "__init__"}
if generated != operations:
    failures.append(
        f"generated endpoint functions {sorted(generated)} != operations {sorted(operations)}"
    )


def check(name, response, model, json_model=True):
    """A 200 whose parsed body is the typed model and, for JSON, gives back what was sent."""
    if response.status_code != 200:
        failures.append(f"{name}: status {response.status_code}: {response.content[:300]!r}")
        return
    if not isinstance(response.parsed, model):
        failures.append(f"{name}: parsed as {type(response.parsed).__name__}, not {model.__name__}")
        return
    if json_model and response.parsed.to_dict() != json.loads(response.content):
        sent = json.loads(response.content)
        back = response.parsed.to_dict()
        lost = sorted(set(sent) ^ set(back)) or [k for k in sent if sent[k] != back.get(k)]
        failures.append(f"{name}: the typed model does not give back the answer: {lost}")
    print(f"ok {name}: 200 {model.__name__}")


M = models
calls = [
    ("healthz", lambda: mod("api.service.healthz").sync_detailed(client=client), M.Health),
    ("presets", lambda: mod("api.service.presets").sync_detailed(client=client), M.Presets),
    (
        "impact",
        lambda: mod("api.impact.impact").sync_detailed(
            client=client,
            body=M.ImpactRequest(velocity_m_s=6.0, rock=M.RockDto(side_length_m=0.25)),
        ),
        M.ImpactResponse,
    ),
    (
        "column",
        lambda: mod("api.column.column").sync_detailed(
            client=client,
            body=M.ColumnRequest(velocity_m_s=5.0, model=M.ColumnModelDto.DECOUPLED),
        ),
        M.ColumnResponse,
    ),
    (
        "migration",
        lambda: mod("api.migration.migration").sync_detailed(
            client=client,
            body=M.MigrationRequest(
                method=M.MethodDto.LUMPED_MASS, release=M.ReleaseDto(drop_height_m=3.27)
            ),
        ),
        M.MigrationResponse,
    ),
    (
        "scene",
        lambda: mod("api.scene.scene").sync_detailed(client=client, body=M.SceneRequest()),
        M.SceneResponse,
    ),
    (
        "spalling",
        lambda: mod("api.spalling.spalling").sync_detailed(
            client=client, body=M.SpallingRequest()
        ),
        M.SpallingResponse,
    ),
    (
        "study",
        lambda: mod("api.study.study").sync_detailed(client=client, body=M.StudyRequest()),
        M.StudyResponse,
    ),
    (
        "calibrate",
        lambda: mod("api.calibrate.calibrate").sync_detailed(
            client=client,
            body=M.CalibrateRequest.from_dict(
                {
                    "base": {"monte_carlo": {"runs": 20}},
                    "observed": {"runout_m": [100.0, 110.0, 119.0]},
                    "parameters": [{"name": "friction_coefficient", "min": 0.1, "max": 0.3}],
                    "search": {"points": 4, "refinements": 0},
                }
            ),
        ),
        M.CalibrateResponse,
    ),
]
for name, call, model in calls:
    try:
        check(name, call(), model)
    except Exception as e:  # a parse failure is a contract failure, reported with the rest
        failures.append(f"{name}: {type(e).__name__}: {e}")

# The problem page is HTML: typed as a string.
try:
    r = mod("api.service.problem").sync_detailed("invalid_input", client=client)
    check("problem", r, str, json_model=False)
except Exception as e:
    failures.append(f"problem: {type(e).__name__}: {e}")

# The batch answers NDJSON, which generators leave unparsed: each line parses as a BatchLine.
try:
    body = M.BatchRequest(
        items=[
            M.BatchItemDto(kind=M.BatchKind.IMPACT, request=M.BatchItemDtoRequest.from_dict({})),
            M.BatchItemDto(
                kind=M.BatchKind.SPALLING, request=M.BatchItemDtoRequest.from_dict({})
            ),
        ]
    )
    lenient = mod("client").Client(base_url=base_url, timeout=60.0)
    r = mod("api.batch.batch").sync_detailed(client=lenient, body=body)
    if r.status_code != 200:
        failures.append(f"batch: status {r.status_code}")
    lines = [M.BatchLine.from_dict(json.loads(x)) for x in r.content.splitlines() if x.strip()]
    results = [
        kind.from_dict(line.result.to_dict())
        for kind, line in zip([M.ImpactResponse, M.SpallingResponse], lines)
    ]
    if [(line.index, line.status) for line in lines] != [(0, 200), (1, 200)]:
        failures.append(f"batch: lines {[(line.index, line.status) for line in lines]}")
    else:
        print(f"ok batch: 200 BatchLine x 2 ({', '.join(type(x).__name__ for x in results)})")
except Exception as e:
    failures.append(f"batch: {type(e).__name__}: {e}")

# An invalid request is a typed problem naming the field's JSON Pointer.
try:
    r = mod("api.impact.impact").sync_detailed(
        client=client, body=M.ImpactRequest(velocity_m_s=-1.0)
    )
    p = r.parsed
    if r.status_code != 422 or not isinstance(p, M.Problem):
        failures.append(f"impact 422: status {r.status_code}, parsed {type(p).__name__}")
    elif p.status != 422 or not any(e.field == "/velocity_m_s" for e in p.errors):
        failures.append(f"impact 422: problem {p.to_dict()}")
    else:
        print(f"ok impact: 422 Problem {p.type_} naming {p.errors[0].field}")
except Exception as e:
    failures.append(f"impact 422: {type(e).__name__}: {e}")

for f in failures:
    print("FAIL", f)
print(f"{len(calls) + 3 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
