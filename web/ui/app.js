// meshflow's browser UI (DESIGN §8): one page, views chosen by the URL's #fragment.
import { api, ApiError, session, loadSession, loggedIn, isCurator, postWithProgress } from './api.js';
import { createViewer, parseMesh } from './viewer.js';
import { OPERATORS, operatorsFor, atomicStep, blockStep, toXml, fromXml, drawFlow, stepOfError } from './workflow.js';

const main = () => document.getElementById('main');
const esc = (s) => String(s ?? '').replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;').replace(/"/g, '&quot;');
const errorText = (e) => (e instanceof ApiError && e.status === 404 && /Not Found|HTTP 404/.test(e.message)
  ? 'this part of the hub is not available (HTTP 404)' : e.message);
let cleanup = [];

function toast(text) {
  const t = document.getElementById('toast');
  t.textContent = text;
  setTimeout(() => { if (t.textContent === text) t.textContent = ''; }, 4000);
}

function view(title, html) {
  document.title = `${title} — meshflow`;
  main().innerHTML = `<h1>${esc(title)}</h1>${html}`;
  return main();
}

let operationsCache = null;
async function operations() {
  if (!operationsCache) operationsCache = (await api('GET', '/api/operations')).operations;
  return operationsCache;
}
async function domains() {
  try { return (await api('GET', '/api/domains')).domains; } catch { return []; }
}
async function datatypes() {
  try { return (await api('GET', '/api/datatypes')).datatypes; } catch { return ['TriangleMesh']; }
}
const options = (list, selected = '') => list.map((v) => {
  const [value, label] = Array.isArray(v) ? v : [v, v];
  return `<option value="${esc(value)}"${value === selected ? ' selected' : ''}>${esc(label)}</option>`;
}).join('');
const domainOptions = (ds) => ds.map((d) => [d.name, d.parent ? `— ${d.label}` : d.label]);

// ---------- home ----------
function home() {
  view('meshflow: workflows for large triangle meshes', `
    <p>meshflow keeps a repository of geometry-processing <strong>workflows</strong> (smoothing, hole filling,
    simplification, repair...) and runs them on the mesh nodes that offer the operations, moving only
    corrections between nodes rather than whole meshes.</p>
    <h2>How to start</h2>
    <ol>
      <li><a href="#/search">Search</a> the repository by text or purpose, or browse every workflow.</li>
      <li>Open a workflow and <a href="#/run">Run</a> it: upload a mesh (OBJ, OFF, PLY, STL) or give its URL,
        watch each step, see input and output in 3D, download the result.</li>
      <li><a href="#/signup">Sign up</a> or <a href="#/login">Log in</a> to <a href="#/new">create a new workflow</a>
        and keep <a href="#/mine">your workflows</a>.</li>
      <li>Ask the repository in <a href="#/sparql">SPARQL</a>, with example queries.</li>
    </ol>`);
}

// ---------- accounts ----------
function accountForm(kind) {
  const signup = kind === 'signup';
  const el = view(signup ? 'Sign up' : 'Log in', `
    <form id="account">
      <label for="acc-name">Name</label><input id="acc-name" type="text" autocomplete="username" required>
      <label for="acc-pass">Password</label><input id="acc-pass" type="password" autocomplete="${signup ? 'new-password' : 'current-password'}" required>
      <p><button type="submit">${signup ? 'Sign up' : 'Log in'}</button></p>
      <p id="acc-error" class="error" role="alert"></p>
    </form>`);
  el.querySelector('#account').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const body = { name: el.querySelector('#acc-name').value.trim(), password: el.querySelector('#acc-pass').value };
    try {
      Object.assign(session, await api('POST', signup ? '/api/users' : '/api/session', body));
      renderNav();
      toast(`Logged in as ${session.name}`);
      location.hash = '#/';
    } catch (e) { el.querySelector('#acc-error').textContent = errorText(e); }
  });
}

async function logout() {
  try { await api('DELETE', '/api/session'); } catch { /* already gone */ }
  Object.assign(session, { name: null, role: 'anonymous', csrf: null });
  renderNav();
  toast('Logged out');
  location.hash = '#/';
}

function renderNav() {
  for (const el of document.querySelectorAll('[data-needs]')) {
    const need = el.dataset.needs;
    const show = need === 'anonymous' ? !loggedIn() : need === 'curator' ? isCurator() : loggedIn();
    el.closest('li').hidden = !show;
  }
  document.getElementById('who').textContent = loggedIn() ? `${session.name} (${session.role})` : '';
}

// ---------- search ----------
async function search(params) {
  const [ds, types, ops] = await Promise.all([domains(), datatypes(), operations().catch(() => [])]);
  const el = view('Search workflows', `
    <form id="search" class="row" role="search">
      <div><label for="s-q">Text</label><input id="s-q" type="text" name="q" value="${esc(params.get('q') || '')}"></div>
      <div><label for="s-domain">Purpose</label><select id="s-domain" name="domain"><option value="">any</option>${options(domainOptions(ds), params.get('domain') || '')}</select></div>
      <div><label for="s-input">Input type</label><select id="s-input" name="input"><option value="">any</option>${options(types, params.get('input') || '')}</select></div>
      <div><label for="s-output">Output type</label><select id="s-output" name="output"><option value="">any</option>${options(types, params.get('output') || '')}</select></div>
      <div><label for="s-op">Operation</label><select id="s-op" name="operation"><option value="">any</option>${options(ops.map((o) => o.name), params.get('operation') || '')}</select></div>
      <div><label for="s-type">Kind</label><select id="s-type" name="type">${options([['', 'any'], ['executable', 'executable'], ['static', 'static (documentation)']], params.get('type') || '')}</select></div>
      <div><button type="submit">Search</button></div>
    </form>
    <div id="results" aria-live="polite"></div>`);
  el.querySelector('#search').addEventListener('submit', (ev) => {
    ev.preventDefault();
    const q = new URLSearchParams();
    for (const [k, v] of new FormData(ev.target)) if (v) q.set(k, v);
    location.hash = `#/search?${q}`;
  });
  await listWorkflows(el.querySelector('#results'), params, false);
}

async function listWorkflows(box, params, mine) {
  box.textContent = 'Searching…';
  try {
    const q = new URLSearchParams(params);
    if (!q.has('limit')) q.set('limit', '50');
    const r = await api('GET', `/api/workflows?${q}`);
    if (!r.workflows.length) { box.innerHTML = '<p>No workflows match.</p>'; return; }
    box.innerHTML = `<p>${r.total} workflow${r.total === 1 ? '' : 's'}</p><div class="table-wrap"><table>
      <thead><tr><th scope="col">Name</th><th scope="col">Purpose</th><th scope="col">Creator</th><th scope="col">Date</th><th scope="col">Kind</th>${mine ? '<th scope="col">Actions</th>' : ''}</tr></thead>
      <tbody>${r.workflows.map((w) => `<tr data-id="${esc(w.id)}"><td><a href="#/workflow/${encodeURIComponent(w.id)}">${esc(w.name)}</a></td>
        <td>${esc((w.domains || []).join(', '))}</td><td>${esc(w.creator)}</td><td>${esc(String(w.created || '').slice(0, 10))}</td><td>${esc(w.type || 'executable')}</td>
        ${mine ? `<td><button type="button" class="danger" data-delete="${esc(w.id)}" aria-label="Delete ${esc(w.name)}">Delete</button></td>` : ''}</tr>`).join('')}</tbody></table></div>`;
    for (const b of box.querySelectorAll('[data-delete]')) b.addEventListener('click', async () => {
      if (!confirm('Delete this workflow?')) return;
      try { await api('DELETE', `/api/workflows/${encodeURIComponent(b.dataset.delete)}`); b.closest('tr').remove(); toast('Deleted'); }
      catch (e) { toast(errorText(e)); }
    });
  } catch (e) { box.innerHTML = `<p class="error" role="alert">Search failed: ${esc(errorText(e))}</p>`; }
}

async function mine() {
  if (!loggedIn()) { location.hash = '#/login'; return; }
  const el = view('My workflows', '<p><a href="#/new">Create a new workflow</a></p><div id="results"></div>');
  await listWorkflows(el.querySelector('#results'), new URLSearchParams({ creator: session.name }), true);
}

// ---------- one workflow ----------
async function workflowPage(id) {
  const el = view('Workflow', '<p>Loading…</p>');
  try {
    const w = await api('GET', `/api/workflows/${encodeURIComponent(id)}`);
    let xml = '';
    if (w.type !== 'static') xml = await (await fetch(`/api/workflows/${encodeURIComponent(id)}/xml`)).text();
    view(w.name, `
      <p>${esc(w.description)}</p>
      <dl><dt>Creator</dt><dd>${esc(w.creator)}</dd><dt>Date</dt><dd>${esc(w.created)}</dd>
        <dt>Purpose</dt><dd>${esc((w.domains || []).join(', '))}</dd>
        <dt>Operations</dt><dd>${esc((w.operations || []).join(', '))}</dd>
        <dt>Input → output</dt><dd>${esc((w.inputs || []).join(', '))} → ${esc((w.outputs || []).join(', '))}</dd></dl>
      ${w.type === 'static' ? '<p class="muted">A documentation workflow: it describes a pipeline and cannot be run here.</p>'
        : `<p><a class="button" href="#/run?workflow=${encodeURIComponent(id)}"><button type="button" tabindex="-1">Run</button></a>
           <a href="/api/workflows/${encodeURIComponent(id)}/xml" download="${esc(w.name)}.xml">Download the XML</a></p>`}
      <h2>Steps</h2><div id="flow"></div>
      ${xml ? `<h2>XML</h2><pre><code>${esc(xml)}</code></pre>` : ''}
      ${loggedIn() && (w.creator === session.name || isCurator()) ? '<p><button type="button" class="danger" id="del">Delete this workflow</button></p>' : ''}`);
    if (xml) main().querySelector('#flow').append(drawFlow(fromXml(xml)));
    else main().querySelector('#flow').textContent = (w.operations || []).join(' → ');
    main().querySelector('#del')?.addEventListener('click', async () => {
      if (!confirm('Delete this workflow?')) return;
      try { await api('DELETE', `/api/workflows/${encodeURIComponent(id)}`); location.hash = '#/mine'; }
      catch (e) { toast(errorText(e)); }
    });
  } catch (e) { el.innerHTML = `<h1>Workflow</h1><p class="error" role="alert">${esc(errorText(e))}</p>`; }
}

// ---------- run ----------
async function runPage(params) {
  const id = params.get('workflow');
  const draft = sessionStorage.getItem('meshflow.draftXml') || '';
  let title = 'Run a workflow';
  if (id) { try { title = `Run: ${(await api('GET', `/api/workflows/${encodeURIComponent(id)}`)).name}`; } catch { /* keep */ } }
  const el = view(title, `
    <form id="run">
      ${id ? `<p>Workflow <a href="#/workflow/${encodeURIComponent(id)}">${esc(id)}</a></p>`
        : `<label for="r-xml">Workflow XML</label><textarea id="r-xml" rows="8" spellcheck="false">${esc(draft)}</textarea>`}
      <label for="r-file">Mesh file (OBJ, OFF, PLY, STL)</label><input id="r-file" type="file" accept=".obj,.off,.ply,.stl">
      <label for="r-url">…or the mesh's URL</label><input id="r-url" type="url" placeholder="https://…/mesh.ply">
      <label for="r-transfer">Between steps send</label>
      <select id="r-transfer">${options([['', 'the hub default'], ['smaller', 'the correction or the mesh, whichever is smaller'], ['output', 'always the whole mesh']])}</select>
      <p><button type="submit" id="r-go">Run</button></p>
      <label for="r-progress">Upload</label><progress id="r-progress" max="100" value="0"></progress> <span id="r-percent">0 %</span>
      <p id="r-error" class="error" role="alert"></p>
    </form>
    <section aria-labelledby="h-progress"><h2 id="h-progress">Progress</h2>
      <p id="j-state" aria-live="polite">Not started.</p>
      <div class="table-wrap"><table><thead><tr><th scope="col">#</th><th scope="col">Operation</th><th scope="col">Node</th><th scope="col">State</th><th scope="col">Sent to later nodes</th><th scope="col">Correction</th><th scope="col">Whole mesh</th><th scope="col">Run ms</th></tr></thead>
      <tbody id="j-steps"></tbody></table></div>
      <p id="j-download"></p>
    </section>
    <section aria-labelledby="h-3d"><h2 id="h-3d">3D view</h2>
      <div class="viewers"><figure id="v-in"></figure><figure id="v-out"></figure></div></section>`);
  const form = el.querySelector('#run');
  let inputViewer = null;
  el.querySelector('#r-file').addEventListener('change', async (ev) => {
    const file = ev.target.files[0];
    if (!file) return;
    try {
      if (!inputViewer) { inputViewer = createViewer(el.querySelector('#v-in'), 'Input'); cleanup.push(() => inputViewer.dispose()); }
      inputViewer.setGeometry(parseMesh(file.name, await file.arrayBuffer()));
    } catch (e) { el.querySelector('#v-in').innerHTML = `<p class="error">Cannot show the input here: ${esc(e.message)}</p>`; }
  });
  form.addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const errorBox = el.querySelector('#r-error');
    errorBox.textContent = '';
    const fd = new FormData();
    if (id) fd.append('workflow_id', id);
    else {
      const xml = el.querySelector('#r-xml').value.trim();
      if (!xml) { errorBox.textContent = 'Give the workflow XML (or open a workflow and press Run).'; return; }
      fd.append('workflow', xml);
    }
    const transfer = el.querySelector('#r-transfer').value;
    if (transfer) fd.append('transfer', transfer);
    const file = el.querySelector('#r-file').files[0];
    const url = el.querySelector('#r-url').value.trim();
    if (file && url) { errorBox.textContent = 'Give a file or a URL, not both.'; return; }
    if (url) fd.append('input_url', url);
    if (file) fd.append('input', file, file.name);
    const bar = el.querySelector('#r-progress'), pct = el.querySelector('#r-percent');
    el.querySelector('#r-go').disabled = true;
    try {
      const job = await postWithProgress('/api/jobs', fd, (done, total) => {
        bar.value = Math.round((100 * done) / total);
        pct.textContent = `${bar.value} % (${(done / 1048576).toFixed(1)} of ${(total / 1048576).toFixed(1)} MiB)`;
      });
      bar.value = 100;
      watchJob(el, job.id);
    } catch (e) {
      errorBox.textContent = `The hub refused the job: ${errorText(e)}`;
    } finally { el.querySelector('#r-go').disabled = false; }
  });
}

function watchJob(el, jobId) {
  const state = el.querySelector('#j-state');
  state.textContent = `Job ${jobId}: queued`;
  const events = new EventSource(`/api/jobs/${jobId}/events`);
  cleanup.push(() => events.close());
  events.onmessage = async (msg) => {
    const job = JSON.parse(msg.data);
    state.textContent = `Job ${jobId}: ${job.state}${job.error ? ` — ${job.error}` : ''} (${(job.elapsed_ms / 1000).toFixed(1)} s)`;
    state.className = job.state === 'failed' ? 'error' : job.state === 'done' ? 'ok' : '';
    el.querySelector('#j-steps').innerHTML = (job.steps || []).map((s, i) => `<tr><td>${i + 1}</td><td>${esc(s.operation)}</td><td>${esc(s.node)}</td><td>${esc(s.state)}</td>
      <td>${esc(s.sent === 'correction' ? 'correction' : s.sent === 'output' ? 'whole mesh' : s.sent || '')}</td><td>${s.correction_bytes ? `${s.correction_bytes.toLocaleString('en')} B` : ''}</td>
      <td>${s.output_bytes ? `${s.output_bytes.toLocaleString('en')} B` : ''}</td><td>${s.run_ms ?? ''}</td></tr>`).join('');
    if (['done', 'failed', 'cancelled'].includes(job.state)) {
      events.close();
      if (job.state === 'done') await showOutput(el, jobId);
    }
  };
  events.onerror = () => { if (events.readyState === EventSource.CLOSED) state.textContent += ' (event stream closed)'; };
}

async function showOutput(el, jobId) {
  el.querySelector('#j-download').innerHTML = `<a id="download" href="/api/jobs/${jobId}/output" download="${jobId}.ply">Download the output (PLY)</a>`;
  try {
    const res = await fetch(`/api/jobs/${jobId}/output`);
    if (!res.ok) throw new Error(`HTTP ${res.status}`);
    const viewer = createViewer(el.querySelector('#v-out'), 'Output');
    cleanup.push(() => viewer.dispose());
    viewer.setGeometry(parseMesh('output.ply', await res.arrayBuffer()));
  } catch (e) { el.querySelector('#v-out').innerHTML = `<p class="error">Cannot show the output: ${esc(e.message)}</p>`; }
}

// ---------- builder ----------
async function builder() {
  let ops;
  try { ops = await operations(); } catch (e) { view('New workflow', `<p class="error" role="alert">${esc(errorText(e))}</p>`); return; }
  const ds = await domains();
  const atomics = ops.filter((o) => o.kind === 'atomic');
  const analyses = ops.filter((o) => o.kind === 'analysis');
  const byName = Object.fromEntries(ops.map((o) => [o.name, o]));
  const state = { steps: [], errors: {} };
  const el = view('New workflow', `
    <form id="builder" novalidate>
      <label for="b-name">Name</label><input id="b-name" type="text" required>
      <label for="b-desc">Description</label><textarea id="b-desc" rows="3"></textarea>
      <fieldset><legend>Purposes</legend><div id="b-domains" class="row">${ds.length ? ds.map((d, i) => `<div><input type="checkbox" id="b-d${i}" value="${esc(d.name)}"> <label for="b-d${i}" style="display:inline">${esc(d.label)}</label></div>`).join('') : '<span class="muted">The hub lists no purposes.</span>'}</div></fieldset>
      <h2>Steps</h2>
      <div id="b-steps"></div>
      <div class="row" id="b-add">
        <div><label for="b-op">Operation</label><select id="b-op">${options(atomics.map((o) => o.name))}</select></div>
        <div><button type="button" id="b-add-op">Add step</button></div>
        <div><button type="button" class="secondary" id="b-add-if">Add if/else block</button></div>
        <div><button type="button" class="secondary" id="b-add-while">Add while loop</button></div>
      </div>
      <p id="b-op-desc" class="muted"></p>
      <h2>Flow</h2><div id="b-flow"></div>
      <p><button type="submit">Save</button> <button type="button" class="secondary" id="b-run">Run without saving</button></p>
      <p id="b-error" class="error" role="alert"></p>
      <details><summary>XML</summary><pre id="b-xml"></pre></details>
    </form>`);
  const opSelect = el.querySelector('#b-op');
  const showDesc = () => { el.querySelector('#b-op-desc').textContent = byName[opSelect.value]?.description || ''; };
  opSelect.addEventListener('change', showDesc); showDesc();

  // Where new steps go: the list chosen by "add here" buttons, the top level by default.
  let target = state.steps;
  const find = (id, list = state.steps) => {
    for (let i = 0; i < list.length; i++) {
      if (list[i].id === id) return { list, i };
      const s = list[i];
      if (s.kind !== 'atomic') { const r = find(id, s.body) || find(id, s.else); if (r) return r; }
    }
    return null;
  };
  el.querySelector('#b-add-op').addEventListener('click', () => { target.push(atomicStep(byName[opSelect.value])); render(); });
  el.querySelector('#b-add-if').addEventListener('click', () => { target.push(blockStep('if', analyses[0])); render(); });
  el.querySelector('#b-add-while').addEventListener('click', () => { target.push(blockStep('while', analyses[0])); render(); });

  function paramField(step, p) {
    const fid = `p-${step.id}-${p.name}`;
    const range = [p.min !== undefined ? `${p.min_exclusive ? '>' : '≥'} ${p.min}` : '', p.max !== undefined ? `≤ ${p.max}` : ''].filter(Boolean).join(', ');
    const numeric = p.type === 'natural' || p.type === 'integer' || p.type === 'real';
    return `<div><label for="${fid}">${esc(p.name)}${p.unit ? ` (${esc(p.unit)})` : ''}</label>
      <input id="${fid}" data-step="${step.id}" data-param="${esc(p.name)}" type="${numeric ? 'number' : 'text'}" ${numeric ? `step="${p.type === 'real' ? 'any' : '1'}"` : ''}
        ${p.min !== undefined ? `min="${p.min}"` : ''} ${p.max !== undefined ? `max="${p.max}"` : ''} value="${esc(step.params[p.name] ?? '')}" aria-describedby="${fid}-h">
      <small id="${fid}-h" class="muted">${esc(p.description || '')}${range ? ` Range ${esc(range)}.` : ''} Default ${esc(p.default ?? 'none')}.</small></div>`;
  }
  function stepHtml(s, list, i) {
    const ctrl = `<div class="row">
      <button type="button" class="secondary" data-move="-1" data-id="${s.id}" ${i === 0 ? 'disabled' : ''} aria-label="Move step up">↑</button>
      <button type="button" class="secondary" data-move="1" data-id="${s.id}" ${i === list.length - 1 ? 'disabled' : ''} aria-label="Move step down">↓</button>
      <button type="button" class="danger" data-remove="${s.id}" aria-label="Remove this step">Remove</button></div>`;
    const err = state.errors[s.id] ? `<p class="step-error" role="alert">${esc(state.errors[s.id])}</p>` : '';
    if (s.kind === 'atomic') {
      const op = byName[s.name];
      return `<div class="step" data-step-id="${s.id}"><strong>${esc(s.name)}</strong> <span class="muted">${esc(op?.description || '')}</span>
        <div class="row">${(op?.params || []).map((p) => paramField(s, p)).join('')}</div>${err}${ctrl}</div>`;
    }
    const a = byName[s.cond.name];
    const vt = a?.value_type || 'real';
    const cid = `c-${s.id}`;
    const branch = (which, items) => `<div class="body" data-branch="${which}" data-id="${s.id}"><p><strong>${which === 'else' ? 'else' : s.kind === 'while' ? 'repeat' : 'then'}</strong>
      <button type="button" class="secondary" data-target="${which}" data-id="${s.id}">Add steps here</button></p>${items.map((c, j) => stepHtml(c, items, j)).join('')}</div>`;
    return `<div class="step ${s.kind}" data-step-id="${s.id}"><strong>${s.kind === 'while' ? 'while' : 'if'}</strong>
      <div class="row">
        <div><label for="${cid}-m">Measure</label><select id="${cid}-m" data-cond="name" data-id="${s.id}">${options(analyses.map((o) => [o.name, `${o.name} (${o.value_type})`]), s.cond.name)}</select></div>
        <div><label for="${cid}-o">Operator</label><select id="${cid}-o" data-cond="op" data-id="${s.id}">${options(operatorsFor(vt), s.cond.op)}</select></div>
        <div><label for="${cid}-v">Value</label>${vt === 'boolean'
          ? `<select id="${cid}-v" data-cond="value" data-id="${s.id}">${options(['true', 'false'], s.cond.value)}</select>`
          : `<input id="${cid}-v" data-cond="value" data-id="${s.id}" type="number" step="${vt === 'natural' ? '1' : 'any'}" ${vt === 'natural' ? 'min="0"' : ''} value="${esc(s.cond.value)}">`}</div>
      </div>${err}${branch('body', s.body)}${s.kind === 'if' ? branch('else', s.else) : ''}${ctrl}</div>`;
  }
  function render() {
    const box = el.querySelector('#b-steps');
    box.innerHTML = state.steps.length ? state.steps.map((s, i) => stepHtml(s, state.steps, i)).join('') : '<p class="muted">No steps yet: choose an operation and add it.</p>';
    const topBtn = document.createElement('button');
    topBtn.type = 'button'; topBtn.className = 'secondary'; topBtn.textContent = 'Add steps at the top level';
    topBtn.addEventListener('click', () => { target = state.steps; toast('New steps go to the top level'); });
    box.append(topBtn);
    for (const b of box.querySelectorAll('[data-target]')) b.addEventListener('click', () => {
      const f = find(Number(b.dataset.id)); target = b.dataset.target === 'else' ? f.list[f.i].else : f.list[f.i].body;
      toast(`New steps go into this ${b.dataset.target === 'else' ? 'else branch' : 'block'}`);
    });
    for (const b of box.querySelectorAll('[data-move]')) b.addEventListener('click', () => {
      const f = find(Number(b.dataset.id)); const j = f.i + Number(b.dataset.move);
      [f.list[f.i], f.list[j]] = [f.list[j], f.list[f.i]]; render();
      box.querySelector(`[data-step-id="${b.dataset.id}"] [data-move="${b.dataset.move}"]`)?.focus();
    });
    for (const b of box.querySelectorAll('[data-remove]')) b.addEventListener('click', () => {
      const f = find(Number(b.dataset.remove)); const removed = f.list.splice(f.i, 1)[0];
      if (removed.body === target || removed.else === target) target = state.steps;
      render();
    });
    for (const inp of box.querySelectorAll('[data-param]')) inp.addEventListener('input', () => { find(Number(inp.dataset.step)).list.find((s) => s.id === Number(inp.dataset.step)).params[inp.dataset.param] = inp.value; refresh(); });
    for (const inp of box.querySelectorAll('[data-cond]')) inp.addEventListener('change', () => {
      const f = find(Number(inp.dataset.id)); const s = f.list[f.i];
      s.cond[inp.dataset.cond] = inp.value;
      if (inp.dataset.cond === 'name') {
        const vt = byName[s.cond.name]?.value_type;
        if (!operatorsFor(vt).includes(s.cond.op)) s.cond.op = 'EQ';
        if (vt === 'boolean' && !['true', 'false'].includes(s.cond.value)) s.cond.value = 'true';
        if (vt !== 'boolean' && isNaN(Number(s.cond.value))) s.cond.value = '0';
        render();
        el.querySelector(`#c-${s.id}-m`)?.focus();
      } else refresh();
    });
    refresh();
  }
  function refresh() {
    const { xml } = toXml(state.steps);
    el.querySelector('#b-xml').textContent = xml;
    const flow = el.querySelector('#b-flow'); flow.innerHTML = ''; flow.append(drawFlow(state.steps));
  }
  render();

  el.querySelector('#b-run').addEventListener('click', () => {
    sessionStorage.setItem('meshflow.draftXml', toXml(state.steps).xml);
    location.hash = '#/run';
  });
  el.querySelector('#builder').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const { xml, owner } = toXml(state.steps);
    const errorBox = el.querySelector('#b-error');
    errorBox.textContent = ''; state.errors = {};
    if (!loggedIn()) { errorBox.textContent = 'Log in or sign up to save workflows.'; return; }
    // The form does not block on the browser's checks (novalidate): the hub validates the
    // workflow and its answer is shown at the step it names.
    if (!el.querySelector('#b-name').value.trim()) { errorBox.textContent = 'Give the workflow a name.'; el.querySelector('#b-name').focus(); return; }
    const body = { name: el.querySelector('#b-name').value.trim(), description: el.querySelector('#b-desc').value.trim(),
      domains: [...el.querySelectorAll('#b-domains input:checked')].map((c) => c.value), xml };
    try {
      const saved = await api('POST', '/api/workflows', body);
      sessionStorage.removeItem('meshflow.draftXml');
      toast('Saved');
      location.hash = `#/workflow/${encodeURIComponent(saved.id)}`;
    } catch (e) {
      const stepId = stepOfError(e.where, owner, state.steps);
      if (stepId) { state.errors[stepId] = e.message; render(); el.querySelector(`[data-step-id="${stepId}"] .step-error`)?.scrollIntoView(); }
      errorBox.textContent = `Not saved: ${errorText(e)}${e.where && e.where.line ? ` (XML line ${e.where.line}${e.where.column ? `, column ${e.where.column}` : ''})` : ''}`;
    }
  });
}

// ---------- curator ----------
async function curator() {
  if (!isCurator()) { view('Curator', '<p>Curator pages need a curator account: <a href="#/login">log in</a>.</p>'); return; }
  const [ds, ops] = await Promise.all([domains(), operations().catch(() => [])]);
  const el = view('Curator', `
    <section aria-labelledby="h-node"><h2 id="h-node">Register a node</h2>
      <form id="node" class="row"><div><label for="n-url">Node URL</label><input id="n-url" type="url" required placeholder="http://host:port"></div>
      <div><button type="submit">Register</button></div></form>
      <div id="n-result" aria-live="polite"></div>
      <h3>Registered nodes</h3><div id="n-list"></div></section>
    <section aria-labelledby="h-static"><h2 id="h-static">Add a documentation (static) workflow</h2>
      <form id="static">
        <label for="st-name">Name</label><input id="st-name" type="text" required>
        <label for="st-desc">Description</label><textarea id="st-desc" rows="3"></textarea>
        <label for="st-domains">Purposes</label><select id="st-domains" multiple size="6">${options(domainOptions(ds))}</select>
        <label for="st-ops">Operations it uses</label><select id="st-ops" multiple size="6">${options(ops.map((o) => o.name))}</select>
        <p><button type="submit">Add</button></p><p id="st-result" role="alert"></p>
      </form></section>`);
  async function listNodes() {
    try {
      const r = await api('GET', '/api/services');
      el.querySelector('#n-list').innerHTML = `<div class="table-wrap"><table><thead><tr><th scope="col">URL</th><th scope="col">Operations</th><th scope="col">Active steps</th><th scope="col">Actions</th></tr></thead><tbody>
        ${r.services.map((s) => `<tr><td>${esc(s.url)}</td><td>${esc(s.operations)}</td><td>${esc(s.active_steps)}</td><td><button type="button" class="danger" data-url="${esc(s.url)}" aria-label="Remove ${esc(s.url)}">Remove</button></td></tr>`).join('')}</tbody></table></div>`;
      for (const b of el.querySelectorAll('#n-list [data-url]')) b.addEventListener('click', async () => {
        try { await api('DELETE', `/api/services?url=${encodeURIComponent(b.dataset.url)}`); listNodes(); } catch (e) { toast(errorText(e)); }
      });
    } catch (e) { el.querySelector('#n-list').textContent = errorText(e); }
  }
  listNodes();
  el.querySelector('#node').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const box = el.querySelector('#n-result');
    try {
      const r = await api('POST', '/api/services', { url: el.querySelector('#n-url').value.trim() });
      operationsCache = null;
      const names = Array.isArray(r.operation_names) ? r.operation_names : null;
      box.innerHTML = `<p class="ok">Registered ${esc(r.url)}: ${names ? `${names.length} operations` : `${esc(r.operations)} operations`}.</p>${names ? `<ul>${names.map((n) => `<li>${esc(n)}</li>`).join('')}</ul>` : ''}`;
      listNodes();
    } catch (e) { box.innerHTML = `<p class="error" role="alert">${esc(errorText(e))}</p>`; }
  });
  el.querySelector('#static').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const picked = (sel) => [...el.querySelector(sel).selectedOptions].map((o) => o.value);
    try {
      const r = await api('POST', '/api/workflows', { type: 'static', name: el.querySelector('#st-name').value.trim(),
        description: el.querySelector('#st-desc').value.trim(), domains: picked('#st-domains'), operations: picked('#st-ops') });
      location.hash = `#/workflow/${encodeURIComponent(r.id)}`;
    } catch (e) { el.querySelector('#st-result').innerHTML = `<span class="error">${esc(errorText(e))}</span>`; }
  });
}

// ---------- SPARQL ----------
const EXAMPLES = [
  ['Workflows and their creators', `PREFIX wo: <http://meshflow.example/ontology/wo#>
SELECT ?workflow ?name ?creator WHERE {
  ?workflow a wo:Workflow ; wo:name ?name .
  OPTIONAL { ?workflow wo:creator ?creator }
} LIMIT 50`],
  ['Any 20 triples', 'SELECT ?s ?p ?o WHERE { ?s ?p ?o } LIMIT 20'],
  ['Classes in use', 'SELECT DISTINCT ?class WHERE { ?s a ?class } LIMIT 50'],
];
function sparqlPage() {
  const el = view('SPARQL', `
    <p>Ask the repository (workflows, operations, purposes) in SPARQL. Examples:</p>
    <div class="row">${EXAMPLES.map(([t], i) => `<button type="button" class="secondary" data-example="${i}">${esc(t)}</button>`).join('')}</div>
    <form id="sparql"><label for="q">Query</label><textarea id="q" rows="8" spellcheck="false">${esc(EXAMPLES[1][1])}</textarea>
      <p><button type="submit">Run query</button></p></form>
    <div id="sparql-results" aria-live="polite"></div>`);
  for (const b of el.querySelectorAll('[data-example]')) b.addEventListener('click', () => { el.querySelector('#q').value = EXAMPLES[b.dataset.example][1]; });
  el.querySelector('#sparql').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const box = el.querySelector('#sparql-results');
    box.textContent = 'Running…';
    try {
      const res = await fetch('/sparql', { method: 'POST', headers: { Accept: 'application/sparql-results+json', 'Content-Type': 'application/x-www-form-urlencoded' },
        body: new URLSearchParams({ query: el.querySelector('#q').value }) });
      const text = await res.text();
      let data; try { data = JSON.parse(text); } catch { data = null; }
      if (!res.ok || !data) throw new Error((data && data.error) || text.slice(0, 300) || `HTTP ${res.status}`);
      const vars = data.head?.vars || [];
      const rows = data.results?.bindings || [];
      if (data.boolean !== undefined) { box.innerHTML = `<p>Answer: <strong>${data.boolean}</strong></p>`; return; }
      box.innerHTML = `<p>${rows.length} row${rows.length === 1 ? '' : 's'}</p><div class="table-wrap"><table><thead><tr>${vars.map((v) => `<th scope="col">${esc(v)}</th>`).join('')}</tr></thead>
        <tbody>${rows.map((r) => `<tr>${vars.map((v) => `<td>${esc(r[v]?.value ?? '')}</td>`).join('')}</tr>`).join('')}</tbody></table></div>`;
    } catch (e) { box.innerHTML = `<p class="error" role="alert">The query failed: ${esc(e.message)}</p>`; }
  });
}

// ---------- routing ----------
async function route() {
  for (const f of cleanup) f();
  cleanup = [];
  const [path, query = ''] = location.hash.replace(/^#/, '').split('?');
  const params = new URLSearchParams(query);
  const parts = path.split('/').filter(Boolean);
  try {
    switch (parts[0]) {
      case undefined: home(); break;
      case 'search': await search(params); break;
      case 'workflow': await workflowPage(decodeURIComponent(parts[1] || '')); break;
      case 'run': await runPage(params); break;
      case 'new': await builder(); break;
      case 'mine': await mine(); break;
      case 'curator': await curator(); break;
      case 'sparql': sparqlPage(); break;
      case 'login': accountForm('login'); break;
      case 'signup': accountForm('signup'); break;
      default: view('Not found', `<p>No page ${esc(path)}. <a href="#/">Home</a></p>`);
    }
  } catch (e) { view('Error', `<p class="error" role="alert">${esc(errorText(e))}</p>`); }
  if (location.hash && location.hash !== '#/') main().focus({ preventScroll: true });
}

window.addEventListener('hashchange', route);
document.getElementById('logout').addEventListener('click', logout);
renderNav();
route();
loadSession().then(renderNav);
