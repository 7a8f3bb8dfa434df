// Type-checked against the types openapi-typescript generates from openapi/openapi.json
// (scripts/clients copies this file beside the generated gangue.d.ts and runs
// `tsc --noEmit --strict`): a typed request for every endpoint, the typed answers, and the exact
// set of paths, so that an endpoint that goes missing or a field that changes type fails.
import type { components, paths } from "./gangue";

type Schemas = components["schemas"];
type Body<P extends keyof paths> = paths[P] extends {
  post: { requestBody: { content: { "application/json": infer B } } };
}
  ? B
  : never;
type Ok<P extends keyof paths, M extends "get" | "post"> = paths[P][M] extends {
  responses: { 200: { content: infer C } };
}
  ? C
  : never;

// The document's paths are exactly these.
type Expected =
  | "/healthz"
  | "/v1/presets"
  | "/problems/{code}"
  | "/v1/impact"
  | "/v1/column"
  | "/v1/migration"
  | "/v1/scene"
  | "/v1/calibrate"
  | "/v1/spalling"
  | "/v1/study"
  | "/v1/batch";
type Same<A, B> = [A] extends [B] ? ([B] extends [A] ? true : false) : false;
export const exactPaths: Same<keyof paths, Expected> = true;

export const impact: Body<"/v1/impact"> = {
  velocity_m_s: 6.0,
  rock: { shape: "cube", side_length_m: 0.25 },
  contact: { law: "paper", effective_modulus: "paper" },
};
export const column: Body<"/v1/column"> = {
  velocity_m_s: 5.0,
  model: "decoupled",
  galerkin: { mode_shapes: "exact" },
};
export const migration: Body<"/v1/migration"> = {
  method: "lumped_mass",
  release: { drop_height_m: 3.27 },
  face: { dip_deg: 45.0, floor: { kind: "plane" } },
};
export const scene: Body<"/v1/scene"> = { method: "lumped_mass", column_model: "decoupled" };
export const spalling: Body<"/v1/spalling"> = {};
export const calibrate: Body<"/v1/calibrate"> = {
  observed: { runout_m: [10.0, 12.0] },
  parameters: [{ name: "friction_coefficient", min: 0.3, max: 0.8 }],
  objective: "ks",
  search: { points: 4, refinements: 1 },
};
export const study: Body<"/v1/study"> = { grid: "one_at_a_time" };
export const batch: Body<"/v1/batch"> = {
  items: [
    { kind: "impact", request: { velocity_m_s: 6.0 } },
    { kind: "spalling", request: {} },
  ],
};

// The answers are typed: a few fields read with their types.
export function readAnswers(
  health: Ok<"/healthz", "get">["application/json"],
  presets: Ok<"/v1/presets", "get">["application/json"],
  page: Ok<"/problems/{code}", "get">["text/html"],
  i: Ok<"/v1/impact", "post">["application/json"],
  c: Ok<"/v1/column", "post">["application/json"],
  m: Ok<"/v1/migration", "post">["application/json"],
  s: Ok<"/v1/scene", "post">["application/json"],
  sp: Ok<"/v1/spalling", "post">["application/json"],
  st: Ok<"/v1/study", "post">["application/json"],
  cal: Ok<"/v1/calibrate", "post">["application/json"],
  line: Ok<"/v1/batch", "post">["application/x-ndjson"],
  problem: Schemas["Problem"],
): number {
  const status: string = health.status;
  const limits: Record<string, unknown> = presets.limits;
  const html: string = page;
  const force: number = i.max_force_n;
  const energy: number = c.kinetic_energy_j;
  const impacts: number = m.impact_count;
  const sceneImpacts: number = s.impacts.length;
  const zones: number = sp.zones.length;
  const version: string = st.model_version;
  const best: number = cal.objective.best;
  const index: number = line.index;
  const pointers: string[] = problem.errors.map((e) => e.field);
  return (
    status.length + Object.keys(limits).length + html.length + force + energy + impacts +
    sceneImpacts + zones + version.length + best + index + pointers.length
  );
}
