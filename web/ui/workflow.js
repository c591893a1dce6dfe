// Workflows as the builder edits them: a list of steps, each an atomic operation, an if/else
// block or a while loop (thesis §5.1, DESIGN §5), written to and read from the workflow XML,
// and drawn as a flow.
let nextId = 1;
export const OPERATORS = ['EQ', 'NEQ', 'GT', 'LT', 'GEQ', 'LEQ'];
export function operatorsFor(valueType) { return valueType === 'boolean' ? ['EQ', 'NEQ'] : OPERATORS; }
export function defaultValueFor(valueType) { return valueType === 'boolean' ? 'true' : '0'; }

export function atomicStep(op) {
  const params = {};
  for (const p of (op && op.params) || []) params[p.name] = p.default === undefined || p.default === null ? '' : String(p.default);
  return { id: nextId++, kind: 'atomic', name: op ? op.name : '', params };
}
export function blockStep(kind, analysis) {
  const cond = { name: analysis ? analysis.name : '', op: 'GT', value: '0' };
  if (analysis && analysis.value_type === 'boolean') { cond.op = 'EQ'; cond.value = 'true'; }
  return { id: nextId++, kind, cond, body: [], else: [] };
}

const esc = (s) => String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;').replace(/"/g, '&quot;');

// The XML, one element per line so that a validation error's line names its step:
// returns { xml, owner } where owner[line] is the step id written on that line.
export function toXml(steps) {
  const lines = ['<workflow>', '<body>'];
  const owner = [null, null, null];
  const put = (text, id) => { lines.push(text); owner[lines.length] = id; };
  const cond = (c) => `<condition><analysis><name>${esc(c.name)}</name><operator>${esc(c.op)}</operator><value>${esc(c.value)}</value></analysis></condition>`;
  function write(list) {
    for (const s of list) {
      if (s.kind === 'atomic') {
        const ps = Object.entries(s.params).filter(([, v]) => String(v).trim() !== '');
        const params = ps.length ? `<parameters>${ps.map(([k, v]) => `<parameter name="${esc(k)}">${esc(String(v).trim())}</parameter>`).join('')}</parameters>` : '';
        put(`<atomic><name>${esc(s.name)}</name>${params}</atomic>`, s.id);
      } else {
        put(`<${s.kind}>${cond(s.cond)}`, s.id);
        put('<body>', s.id);
        write(s.body);
        put('</body>', s.id);
        if (s.kind === 'if' && s.else.length) { put('<else>', s.id); write(s.else); put('</else>', s.id); }
        put(`</${s.kind}>`, s.id);
      }
    }
  }
  write(steps);
  lines.push('</body>', '</workflow>');
  return { xml: lines.join('\n') + '\n', owner };
}

// The step a hub validation error names: by the XML line (where.line, via toXml's owner), else
// the first step using the operation the error names (where.operation); null when neither.
export function stepOfError(where, owner, steps) {
  if (!where) return null;
  if (where.line && owner[where.line]) return owner[where.line];
  if (!where.operation) return null;
  const find = (list) => {
    for (const s of list) {
      if ((s.kind === 'atomic' ? s.name : s.cond.name) === where.operation) return s.id;
      if (s.kind !== 'atomic') { const r = find(s.body) || find(s.else); if (r) return r; }
    }
    return null;
  };
  return find(steps);
}

// The steps of a workflow XML (for drawing it and opening it in the builder).
export function fromXml(xml) {
  const doc = new DOMParser().parseFromString(xml, 'application/xml');
  if (doc.querySelector('parsererror')) throw new Error('the workflow XML is not well-formed');
  const kids = (el, tag) => [...el.children].filter((c) => c.tagName === tag);
  const text = (el, tag) => { const k = kids(el, tag)[0]; return k ? k.textContent.trim() : ''; };
  function readBody(body) {
    if (!body) return [];
    return [...body.children].map((el) => {
      if (el.tagName === 'atomic') {
        const params = {};
        const ps = kids(el, 'parameters')[0];
        (ps ? kids(ps, 'parameter') : []).forEach((p, i) => { params[p.getAttribute('name') || `#${i + 1}`] = p.textContent.trim(); });
        return { id: nextId++, kind: 'atomic', name: text(el, 'name'), params };
      }
      const a = el.querySelector(':scope > condition > analysis');
      const cond = { name: a ? text(a, 'name') : '', op: a ? text(a, 'operator') || 'EQ' : 'EQ', value: a ? text(a, 'value') : '' };
      return { id: nextId++, kind: el.tagName, cond, body: readBody(kids(el, 'body')[0]), else: readBody(kids(el, 'else')[0]) };
    });
  }
  return readBody(kids(doc.documentElement, 'body')[0]);
}

// The steps drawn as a flow: boxes and arrows, if/else and while as framed blocks.
export function drawFlow(steps) {
  const root = document.createElement('div');
  root.className = 'flow';
  root.setAttribute('role', 'list');
  root.setAttribute('aria-label', 'Steps of the workflow');
  const condText = (c) => `${c.name} ${c.op} ${c.value}`;
  function add(parent, list) {
    list.forEach((s, i) => {
      if (i > 0) { const a = document.createElement('div'); a.className = 'arrow'; a.textContent = '↓'; a.setAttribute('aria-hidden', 'true'); parent.append(a); }
      const el = document.createElement('div');
      el.setAttribute('role', 'listitem');
      if (s.kind === 'atomic') {
        el.className = 'node';
        const ps = Object.entries(s.params).map(([k, v]) => `${k}=${v}`).join(', ');
        el.textContent = s.name + (ps ? ` (${ps})` : '');
      } else {
        el.className = `block ${s.kind}`;
        const head = document.createElement('div');
        head.innerHTML = `<strong>${s.kind === 'while' ? 'while' : 'if'}</strong> ${esc(condText(s.cond))}`;
        const body = document.createElement('div'); body.className = 'branch flow';
        add(body, s.body);
        el.append(head, body);
        if (s.kind === 'if' && s.else.length) {
          const e = document.createElement('div'); e.innerHTML = '<strong>else</strong>';
          const eb = document.createElement('div'); eb.className = 'branch flow';
          add(eb, s.else);
          el.append(e, eb);
        }
        if (s.kind === 'while') { const back = document.createElement('div'); back.className = 'muted'; back.textContent = '↺ repeat while the condition holds'; el.append(back); }
      }
      parent.append(el);
    });
  }
  add(root, steps);
  if (!steps.length) root.textContent = 'No steps.';
  return root;
}
