#!/usr/bin/python3
"""Real SPARQL clients (SPARQLWrapper, rdflib's SPARQLStore, roqet -p) and raw HTTP against a
started `meshflow hub`; bad input included. Usage: clients_test.py MESHFLOW_BINARY.
The hub is stopped on every exit path; the whole test is bounded to 120 s."""
import json, os, shutil, signal, subprocess, sys, tempfile, time, urllib.error, urllib.parse, urllib.request

signal.alarm(120)
binary = sys.argv[1]
data = tempfile.mkdtemp(prefix="mf-sparql-")
# The first curator comes from the shell, before the hub starts.
add = subprocess.run([binary, "user", "add", "cura", "--role", "curator", "--data", data],
                     input="curator-pass\n", capture_output=True, text=True, timeout=60)
if add.returncode != 0:
    sys.exit("meshflow user add failed: " + add.stderr)
hub = subprocess.Popen([binary, "hub", "--port", "0", "--data", data],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
failures = []

def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)

def http(method, path, body=None, headers=None):
    req = urllib.request.Request(url + path, data=body, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, r.headers.get("Content-Type", ""), r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers.get("Content-Type", ""), e.read()

try:
    line = hub.stdout.readline()
    check(line.startswith("meshflow: ready at "), "hub ready line: " + line.strip())
    url = line.split()[-1]
    endpoint = url + "/sparql"
    wo = "PREFIX wo: <http://meshflow.org/ontology/wo#>\n"

    from SPARQLWrapper import SPARQLWrapper, JSON, XML, CSV, TSV, TURTLE
    s = SPARQLWrapper(endpoint)
    s.setQuery(wo + "SELECT ?w ?n WHERE { ?w a wo:WorkflowExecutable ; wo:name ?n }")
    s.setReturnFormat(JSON)
    rows = s.query().convert()["results"]["bindings"]
    check(len(rows) == 4, f"SPARQLWrapper JSON: {len(rows)} executable workflows (want 4)")
    s.setReturnFormat(XML)
    check(len(s.query().convert().getElementsByTagName("result")) == 4, "SPARQLWrapper XML")
    s.setReturnFormat(CSV)
    csv = s.query().convert().decode().strip().splitlines()
    check(csv[0].strip() == "w,n" and len(csv) == 5, "SPARQLWrapper CSV")
    s.setReturnFormat(TSV)
    check(len(s.query().convert().decode().strip().splitlines()) == 5, "SPARQLWrapper TSV")
    s.setMethod("POST")
    s.setReturnFormat(JSON)
    check(len(s.query().convert()["results"]["bindings"]) == 4, "SPARQLWrapper POST form")
    s2 = SPARQLWrapper(endpoint)
    s2.setQuery(wo + "CONSTRUCT { ?w wo:name ?n } WHERE { ?w a wo:WorkflowExecutable ; wo:name ?n }")
    s2.setReturnFormat(TURTLE)
    ttl = s2.query().convert()
    check(b"Mesh Repairing" in ttl, "SPARQLWrapper CONSTRUCT as Turtle")
    s2.setQuery("ASK { ?s ?p ?o }")
    s2.setReturnFormat(JSON)
    check(s2.query().convert().get("boolean") is True, "ASK as JSON")

    import rdflib
    from rdflib.plugins.stores.sparqlstore import SPARQLStore
    g = rdflib.Graph(store=SPARQLStore(endpoint, returnFormat="json"))
    n = len(list(g.query("SELECT ?s WHERE { ?s ?p ?o } LIMIT 5")))
    check(n == 5, f"rdflib SPARQLStore: {n} rows (want 5)")

    roqet = subprocess.run(["roqet", "-q", "-p", endpoint, "-r", "csv", "-e",
                            wo + "SELECT ?n WHERE { ?w wo:name ?n ; wo:workflowDomain wo:Repair }"],
                           capture_output=True, text=True, timeout=30)
    check(roqet.returncode == 0 and "Mesh Repairing" in roqet.stdout,
          f"roqet -p (rc {roqet.returncode}): {roqet.stderr.strip()[:120]}")

    # Raw protocol and bad input.
    q = urllib.parse.quote("SELECT ?s WHERE { ?s ?p ?o } LIMIT 1")
    code, ctype, _ = http("GET", "/sparql?query=" + q, headers={
        "Accept": "application/sparql-results+xml;q=0.9, application/sparql-results+json;q=0.3"})
    check(code == 200 and "xml" in ctype, f"q-weighted Accept picks XML ({ctype})")
    code, _, _ = http("POST", "/sparql", b"SELECT ?s WHERE { ?s ?p ?o } LIMIT 1",
                      {"Content-Type": "application/sparql-query"})
    check(code == 200, "POST application/sparql-query")
    code, _, _ = http("GET", "/sparql?query=" + q, headers={"Accept": "image/png"})
    check(code == 406, f"unacceptable Accept -> 406 (got {code})")
    code, _, body = http("POST", "/sparql", b"INSERT DATA { <urn:a> <urn:b> <urn:c> }",
                         {"Content-Type": "application/sparql-update"})
    check(code == 403, f"update refused (got {code})")
    code, _, body = http("POST", "/sparql", b"query=" + urllib.parse.quote("DELETE WHERE { ?s ?p ?o }").encode(),
                         {"Content-Type": "application/x-www-form-urlencoded"})
    check(code == 403, f"update in the query field refused (got {code})")
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote("SELEC ?x WHERE"))
    check(code == 400 and "error" in json.loads(body), f"syntax error -> 400 JSON (got {code})")
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote(
        "SELECT ?c WHERE { ?c <http://www.w3.org/2000/01/rdf-schema#subClassOf>* ?p }"))
    check(code == 400, f"property path -> 400 (got {code}) {body[:100]}")
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote(
        "SELECT * WHERE { ?a ?b ?c . ?d ?e ?f }"))
    check(code == 413 and b"rows" in body, f"too many rows -> 413, no silent truncation (got {code})")
    code, _, _ = http("POST", "/sparql", b"SELECT * WHERE { ?s ?p ?o } #" + b"x" * (2 << 20),
                      {"Content-Type": "application/sparql-query"})
    check(code == 413, f"oversized body -> 413 (got {code})")
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote(
        "SELECT * WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i . ?j ?k ?l } LIMIT 100000000"))
    check(code in (413, 503), f"a query that runs too long is stopped (got {code}) {body[:100]}")
    # Sorting a cross product computes all of it before the first row: only the deadline stops it,
    # and the store is free at once for the next query.
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote(
        "SELECT ?a WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i } ORDER BY ?c ?f ?i LIMIT 1"))
    check(code == 503, f"a runaway query -> 503 (got {code}) {body[:100]}")
    started = time.monotonic()
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote("ASK { ?s ?p ?o }"))
    took = time.monotonic() - started
    check(code == 200 and took < 1.0, f"the next query answers within 1 s (took {took:.2f} s, {code})")

    # Search and the workflow routes.
    code, _, body = http("GET", "/api/workflows?runnable=true")
    check(code == 200 and json.loads(body)["total"] == 0, f"runnable=true with no node registered: none ({body[:100]})")
    code, _, body = http("GET", "/api/workflows?runnable=false")
    check(code == 200 and json.loads(body)["total"] == 4, f"runnable=false: all four ({body[:100]})")
    code, _, _ = http("GET", "/api/workflows?runnable=maybe")
    check(code == 400, f"runnable=maybe -> 400 (got {code})")
    code, _, body = http("GET", "/api/workflows?domain=Repair")
    names = [w["name"] for w in json.loads(body)["workflows"]]
    check(code == 200 and "Mesh Repairing" in names, f"domain=Repair finds Mesh Repairing: {names}")
    code, _, body = http("GET", "/api/workflows?q=repair&limit=1")
    d = json.loads(body)
    check(d["total"] == 2 and len(d["workflows"]) == 1 and d["workflows"][0]["id"] in ("mesh-repairing", "conditional-repair"),
          f"q=repair ranked and paged: {d}")
    code, _, body = http("GET", "/api/workflows?domain=Nope")
    check(code == 400, f"unknown domain -> 400 (got {code})")
    code, _, body = http("GET", "/api/workflows?limit=abc")
    check(code == 400, f"bad limit -> 400 (got {code})")
    code, _, body = http("GET", "/api/workflows/mesh-repairing")
    d = json.loads(body)
    check(code == 200 and d["inputs"] == ["TriangleMesh"] and len(d["operations"]) == 4, f"workflow detail {d}")
    code, ctype, body = http("GET", "/api/workflows/mesh-repairing/xml")
    check(code == 200 and b"FillHoles" in body and "xml" in ctype, "workflow XML")
    code, _, body = http("GET", "/api/domains")
    doms = {x["name"]: x["parent"] for x in json.loads(body)["domains"]}
    check(doms.get("HoleFilling") == "Repair" and doms.get("Repair") is None, "GET /api/domains")
    code, _, body = http("GET", "/api/datatypes")
    check("TriangleMesh" in json.loads(body)["datatypes"], "GET /api/datatypes")
    code, ctype, body = http("GET", "/ontology/wo")
    check(code == 200 and b"WorkflowExecutable" in body, "GET /ontology/wo")
    code, _, _ = http("DELETE", "/api/workflows/mesh-repairing")
    check(code == 401, f"anonymous delete refused (got {code})")
    code, _, _ = http("GET", "/api/workflows/mesh-repairing")
    check(code == 200, "the example is still there")

    # Accounts: sign-up logs in; cookie writes need the CSRF header; tokens need none.
    def account(name, password):
        code, _, body = http("POST", "/api/users", json.dumps({"name": name, "password": password}).encode(),
                             {"Content-Type": "application/json"})
        return code, body
    code, body = account("alice", "alice-pass")
    check(code == 201 and json.loads(body)["role"] == "user", f"sign-up (got {code})")
    code, body = account("alice", "other-pass")
    check(code == 400, f"a taken name is refused (got {code})")
    code, body = account("bob", "short")
    check(code == 400, f"a short password is refused (got {code})")
    def login(name, password):
        req = urllib.request.Request(url + "/api/session", method="POST",
                                     data=json.dumps({"name": name, "password": password}).encode(),
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=30) as r:
                cookie = r.headers["Set-Cookie"].split(";")[0]
                return r.status, cookie, json.loads(r.read())["csrf"], r.headers["Set-Cookie"]
        except urllib.error.HTTPError as e:
            return e.code, None, None, None
    code, _, _, _ = login("alice", "wrong-pass")
    check(code == 401, f"wrong password -> 401 (got {code})")
    code, cookie, csrf, setc = login("alice", "alice-pass")
    check(code == 200 and "HttpOnly" in setc and "SameSite=Strict" in setc, f"log-in sets the cookie ({setc})")
    wf = {"name": "Alice smooths", "description": "Two smoothing steps for scans",
          "domains": ["Smoothing"],
          "xml": "<workflow><body><atomic><name>LaplacianSmoothing</name></atomic></body></workflow>"}
    jh = {"Content-Type": "application/json", "Cookie": cookie}
    code, _, _ = http("POST", "/api/workflows", json.dumps(wf).encode(), jh)
    check(code == 403, f"cookie POST without CSRF -> 403 (got {code})")
    code, _, body = http("POST", "/api/workflows", json.dumps(wf).encode(), dict(jh, **{"X-CSRF-Token": csrf}))
    check(code == 201, f"create with CSRF -> 201 (got {code}) {body[:150]}")
    alice_id = json.loads(body)["id"] if code == 201 else "none"
    code, _, body = http("GET", "/api/workflows?creator=alice")
    check([w["id"] for w in json.loads(body)["workflows"]] == [alice_id], "search by creator")
    bad = dict(wf, xml="<workflow><body>\n<atomic><name>Frobnicate</name></atomic></body></workflow>")
    code, _, body = http("POST", "/api/workflows", json.dumps(bad).encode(), dict(jh, **{"X-CSRF-Token": csrf}))
    where = json.loads(body).get("where", {})
    check(code == 400 and where.get("line") == 2, f"unknown operation -> 400 with line ({code} {body[:160]})")
    check(where.get("operation") == "Frobnicate" and json.loads(body).get("operation") == "Frobnicate",
          f"the error names the step's operation ({body[:160]})")
    bad = dict(wf, xml="<workflow><body>")
    code, _, body = http("POST", "/api/workflows", json.dumps(bad).encode(), dict(jh, **{"X-CSRF-Token": csrf}))
    check(code == 400 and "line" in json.loads(body).get("where", {}), f"malformed XML -> 400 with line ({code})")
    code, _, body = http("POST", "/api/workflows", b"{" + b" " * (2 << 20) + b"}", dict(jh, **{"X-CSRF-Token": csrf}))
    check(code == 413, f"oversized workflow body -> 413 (got {code})")
    static = {"name": "Print prep", "description": "docs", "domains": ["Printing3D"], "type": "static",
              "operations": ["FillHoles"]}
    code, _, _ = http("POST", "/api/workflows", json.dumps(static).encode(), dict(jh, **{"X-CSRF-Token": csrf}))
    check(code == 403, f"a user cannot file a static workflow (got {code})")
    code, _, body = http("POST", "/api/tokens", b"", {"Cookie": cookie, "X-CSRF-Token": csrf})
    check(code == 201, f"API token (got {code})")
    token = json.loads(body)["token"]
    code, _, body = http("POST", "/api/workflows", json.dumps(dict(wf, name="By token")).encode(),
                         {"Content-Type": "application/json", "Authorization": "Bearer " + token})
    check(code == 201, f"create with a bearer token, no CSRF (got {code})")
    code, _, _ = http("DELETE", "/api/workflows/mesh-repairing", headers={"Authorization": "Bearer " + token})
    check(code == 403, f"a user cannot delete another's workflow (got {code})")
    code, _, _ = http("DELETE", "/api/workflows/" + alice_id, headers={"Authorization": "Bearer nope"})
    check(code == 401, f"unknown token -> 401 (got {code})")
    code, _, _ = http("DELETE", "/api/workflows/" + alice_id, headers={"Cookie": cookie, "X-CSRF-Token": csrf})
    check(code == 204, f"the creator deletes (got {code})")
    code, _, _ = http("GET", "/api/workflows/" + alice_id)
    check(code == 404, f"deleted workflow is gone (got {code})")
    code, ccur, ccsrf, _ = login("cura", "curator-pass")
    code, _, body = http("POST", "/api/workflows", json.dumps(static).encode(),
                         {"Content-Type": "application/json", "Cookie": ccur, "X-CSRF-Token": ccsrf})
    check(code == 201 and json.loads(body)["type"] == "static", f"curator files a static workflow ({code})")
    code, _, body = http("GET", "/api/workflows?type=static")
    check(json.loads(body)["total"] == 1, "type=static finds it")
    code, _, _ = http("GET", "/api/session", headers={"Cookie": cookie})
    check(code == 200, "GET /api/session")
    code, _, _ = http("DELETE", "/api/session", headers={"Cookie": cookie, "X-CSRF-Token": csrf})
    check(code == 204, f"log-out (got {code})")
    code, _, _ = http("GET", "/api/session", headers={"Cookie": cookie})
    check(code == 401, f"logged out -> 401 (got {code})")
    code, _, body = http("GET", "/sparql?query=" + urllib.parse.quote(
        "SELECT ?p ?o WHERE { <http://meshflow.org/user/alice> ?p ?o }"))
    check(b"alice" in body and b"argon" not in body.lower(), "users are RDF, without secrets")
finally:
    hub.send_signal(signal.SIGTERM)
    try:
        hub.wait(timeout=15)
    except subprocess.TimeoutExpired:
        hub.kill()
        hub.wait()
    shutil.rmtree(data, ignore_errors=True)

if failures:
    sys.exit(f"{len(failures)} failed: {failures}")
