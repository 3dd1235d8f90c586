// jsonloc.js - where each JSON pointer's value sits in a JSON text, so that an error at
// "/particles/0/size" can be shown next to (and select) that text in the editor.
//
// locate(text) -> {spans: Map(pointer -> {start, end, keyStart}), error: null}
//              or {spans, error: {message, offset}} for a syntax error.
// lineCol(text, offset) -> {line, col} (1-based).

export function locate(text) {
  const spans = new Map();
  let i = 0;
  const fail = (message) => {
    const e = new Error(message);
    e.offset = i;
    throw e;
  };
  const ws = () => {
    while (i < text.length && ' \t\r\n'.includes(text[i])) i++;
  };
  const esc = (tok) => tok.replace(/~/g, '~0').replace(/\//g, '~1');
  const string = () => {
    if (text[i] !== '"') fail('expected a string');
    const start = i++;
    while (i < text.length && text[i] !== '"') {
      if (text[i] === '\\') i++;
      else if (text[i] === '\n') fail('unterminated string');
      i++;
    }
    if (i >= text.length) fail('unterminated string');
    i++;
    return JSON.parse(text.slice(start, i));
  };
  const value = (ptr, keyStart) => {
    ws();
    const start = i;
    const c = text[i];
    if (c === '{') {
      i++;
      ws();
      if (text[i] === '}') i++;
      else {
        for (;;) {
          ws();
          const ks = i;
          const k = string();
          ws();
          if (text[i] !== ':') fail(`expected ':' after "${k}"`);
          i++;
          value(`${ptr}/${esc(k)}`, ks);
          ws();
          if (text[i] === ',') { i++; continue; }
          if (text[i] === '}') { i++; break; }
          fail("expected ',' or '}'");
        }
      }
    } else if (c === '[') {
      i++;
      ws();
      if (text[i] === ']') i++;
      else {
        for (let n = 0; ; n++) {
          value(`${ptr}/${n}`);
          ws();
          if (text[i] === ',') { i++; continue; }
          if (text[i] === ']') { i++; break; }
          fail("expected ',' or ']'");
        }
      }
    } else if (c === '"') {
      string();
    } else {
      const m = /^(-?(0|[1-9]\d*)(\.\d+)?([eE][+-]?\d+)?|true|false|null)/.exec(text.slice(i, i + 64));
      if (!m) fail(i >= text.length ? 'unexpected end of text' : `unexpected '${c}'`);
      i += m[0].length;
    }
    spans.set(ptr, { start, end: i, keyStart: keyStart ?? start });
  };
  try {
    value('');
    ws();
    if (i < text.length) fail('unexpected text after the end');
    return { spans, error: null };
  } catch (e) {
    return { spans, error: { message: e.message, offset: e.offset ?? i } };
  }
}

export function lineCol(text, offset) {
  const before = text.slice(0, offset);
  const line = before.split('\n').length;
  return { line, col: offset - before.lastIndexOf('\n') };
}

// The span of the pointer, or of its nearest existing parent (an error about a missing member
// points at the object that lacks it).
export function spanFor(spans, pointer) {
  let p = pointer;
  for (;;) {
    if (spans.has(p)) return { span: spans.get(p), exact: p === pointer };
    if (!p) return null;
    p = p.slice(0, p.lastIndexOf('/'));
  }
}
