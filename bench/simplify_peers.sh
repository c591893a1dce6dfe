# Sourced by simplify_bench.sh and parallel_quality_bench.sh (not a bench itself): runs one
# simplifier as a whole process and measures it. Needs MF, OUT, TIMEOUT and IN (the input, for
# the error) set by the caller.

mlx() {  # mlx FACES -> script path
  cat >"$OUT/qecd.mlx" <<MLX
<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Simplification: Quadric Edge Collapse Decimation">
  <Param type="RichInt" value="$1" name="TargetFaceNum"/>
  <Param type="RichFloat" value="0" name="TargetPerc"/>
  <Param type="RichFloat" value="0.3" name="QualityThr"/>
  <Param type="RichBool" value="true" name="PreserveBoundary"/>
  <Param type="RichFloat" value="1" name="BoundaryWeight"/>
  <Param type="RichBool" value="false" name="PreserveNormal"/>
  <Param type="RichBool" value="false" name="PreserveTopology"/>
  <Param type="RichBool" value="true" name="OptimalPlacement"/>
  <Param type="RichBool" value="false" name="PlanarQuadric"/>
  <Param type="RichFloat" value="0.001" name="PlanarWeight"/>
  <Param type="RichBool" value="false" name="QualityWeight"/>
  <Param type="RichBool" value="true" name="AutoClean"/>
  <Param type="RichBool" value="false" name="Selected"/>
 </filter>
</FilterScript>
MLX
  echo "$OUT/qecd.mlx"
}

run() {  # run OUTPUT CMD... ; prints "seconds MB vertices mean_error" or "failed"
  local out=$1; shift
  rm -f "$out"
  if ! timeout "$TIMEOUT" /usr/bin/time -f "%e %M" -o "$OUT/t.txt" "$@" >"$OUT/run.log" 2>&1 || [ ! -s "$out" ]; then
    echo "failed - - -"; return
  fi
  read s kb <"$OUT/t.txt"
  local nv err
  nv=$("$MF" op NumberOfVertices "$out" 2>/dev/null || echo "?")
  err=$("$MF" compare "$IN" "$out" --json 2>/dev/null | python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.5f" % ((d["mean_ab"] + d["mean_ba"]) / 2))' 2>/dev/null || echo "?")
  echo "$s $((kb / 1024)) $nv $err"
}

# peers V: the in-core peers at V output vertices, one "name seconds MB vertices error" line each;
# PEERS (default "meshlab openmesh cgal") picks some, the others read "skipped".
peers() {
  local v=$1 bin picked=" ${PEERS:-meshlab openmesh cgal} "
  bin=$(dirname "$MF")/bench
  for p in meshlab openmesh cgal; do
    if [[ $picked != *" $p "* ]]; then echo "$p skipped - - -"; continue; fi
    case $p in
      meshlab) echo "meshlab $(run "$OUT/ml.ply" xvfb-run -a meshlabserver -i "$IN" -o "$OUT/ml.ply" -s "$(mlx $((2 * v)))")" ;;
      openmesh) echo "openmesh $(run "$OUT/om.ply" OpenMesh-commandlineDecimater -M Q -n -$v -i "$IN" -o "$OUT/om.ply")" ;;
      cgal) echo "cgal $(run "$OUT/cg.ply" "$bin/cgal_simplify" "$IN" "$OUT/cg.ply" $v)" ;;
    esac
  done
}
