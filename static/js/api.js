// Talking to the gangue REST API (api.md): JSON requests in SI units,
// problem+json errors (RFC 9457), and NDJSON progress streams.

/**
 * POST a JSON body. Resolves to `{ok: true, status, data}` or
 * `{ok: false, status, problem}`; never throws for HTTP errors, only for
 * an abort. A network failure becomes a synthetic problem.
 *
 * With `onProgress`, asks for `Accept: application/x-ndjson` and reads the
 * stream of `{"progress": {"done", "total"}}` lines followed by exactly one
 * `{"result": …}` or `{"problem": …}` line. A server that answers plain JSON
 * anyway is handled too.
 */
export async function postJson(path, body, { onProgress, signal } = {}) {
  let response;
  try {
    response = await fetch(path, {
      method: 'POST',
      headers: {
        'Content-Type': 'application/json',
        Accept: onProgress ? 'application/x-ndjson' : 'application/json',
      },
      body: JSON.stringify(body),
      signal,
    });
  } catch (err) {
    if (err.name === 'AbortError') throw err;
    return { ok: false, status: 0, problem: networkProblem(err) };
  }

  const type = response.headers.get('content-type') || '';
  if (type.includes('application/x-ndjson')) {
    return readNdjson(response, onProgress);
  }

  const text = await response.text();
  let json = null;
  try {
    json = text ? JSON.parse(text) : null;
  } catch {
    json = null;
  }
  if (response.ok && json !== null) return { ok: true, status: response.status, data: json };
  return { ok: false, status: response.status, problem: asProblem(json, response, text) };
}

/** GET a JSON document; resolves to the parsed body or null. */
export async function getJson(path) {
  try {
    const response = await fetch(path, { headers: { Accept: 'application/json' } });
    return response.ok ? await response.json() : null;
  } catch {
    return null;
  }
}

async function readNdjson(response, onProgress) {
  const reader = response.body.getReader();
  const decoder = new TextDecoder();
  let buffer = '';
  let outcome = null;

  const handleLine = (line) => {
    if (!line.trim()) return;
    const message = JSON.parse(line);
    if (message.progress && onProgress) onProgress(message.progress);
    else if ('result' in message) outcome = { ok: true, status: response.status, data: message.result };
    else if ('problem' in message) {
      outcome = { ok: false, status: message.problem.status || response.status, problem: message.problem };
    }
  };

  for (;;) {
    const { value, done } = await reader.read();
    if (done) break;
    buffer += decoder.decode(value, { stream: true });
    let newline;
    while ((newline = buffer.indexOf('\n')) >= 0) {
      handleLine(buffer.slice(0, newline));
      buffer = buffer.slice(newline + 1);
    }
  }
  buffer += decoder.decode();
  handleLine(buffer);

  return outcome ?? {
    ok: false,
    status: response.status,
    problem: {
      type: 'about:blank',
      title: 'Incomplete answer',
      status: response.status,
      detail: 'The progress stream ended without a result line.',
    },
  };
}

function asProblem(json, response, text) {
  if (json && typeof json === 'object' && ('title' in json || 'type' in json)) return json;
  return {
    type: 'about:blank',
    title: response.statusText || 'Unexpected answer',
    status: response.status,
    detail: text && text.length < 300 ? text : `The server answered HTTP ${response.status}.`,
  };
}

function networkProblem(err) {
  return {
    type: 'about:blank',
    title: 'No answer from the server',
    status: 0,
    detail: `The request could not be sent (${err.message}). Is the server running?`,
  };
}
