# The `service` figure of scripts/bench (sourced by it; uses its helpers and variables, and
# ratio_of / cluster_down_all of bench/cluster.sh): the wall as a service (`dfbwall serve`, README
# "A wall that stays up") across emulated hosts (scripts/cluster). Needs root.
#  1. 1 Gbit/s links, the 2x2 1080p wall on wall1/wall2, 2 render hosts, pattern uncompressed:
#     today's single-job route mode (one mpirun over every host) vs `dfbwall serve` on the wall
#     hosts and a job of the render hosts (`--connect wall1:PORT --codec raw`), interleaved.
#  2. 100 Mbit/s links, path tracer (builtin:cornell) and scivis (builtin:wavelet), codecs
#     jpeg:90, snappy, raw: frame rate, bytes per frame, PSNR of the JPEG captures against the
#     raw captures of the same frame (same seed, frames, camera), and snappy's (lossless) too.
#  3. The relay's cost at 1 Gbit/s (bench/service_relay.sh): the same job straight to the wall and
#     through `dfbwall relay` on a gateway, with 2 render hosts and with 1, interleaved.
#  4. The cost of CURVE at 1 Gbit/s: the same jobs (pattern raw, path tracer snappy) on a wall
#     serving PLAIN and on one serving CURVE (serve --curve, jobs --server-key), interleaved.
#  5. Several jobs at once at 1 Gbit/s: a pattern job (raw) in the wall's left half alone, then
#     it and another in the right half at once (serve's default --max-jobs): each job's frame rate
#     and the pixels per second the wall receives, together over alone (goal >= 0.9x).
# BENCH_SERVICE_PARTS (default "route codecs relay curve jobs") runs some of them only.
# Launching only some of a cluster's ranks: scripts/cluster up writes one mpirun for every rank
# (render ranks 0..R-1, then the wall processes). service_subset writes beside it a hostfile, a
# rankfile and an mpirun for the ranks of one role only (same agent, same TCP settings): the
# wall-only mpirun starts serve on wall1/wall2 (its ranks 0..3 are the layout's processes 0..3),
# the render-only one the job on render1/render2. Both run from the root namespace: the agent
# starts each host's daemon inside that host's namespace, so every rank is on its emulated host.

# service_subset STATE NAME FIRST COUNT: STATE/NAME-mpirun runs ranks FIRST..FIRST+COUNT-1 of the
# cluster's placement (STATE/rank-hosts) as ranks 0..COUNT-1.
service_subset() {
  local state=$1 name=$2 first=$3 count=$4 prefix
  prefix=$(awk 'NR == 1 {sub(/-[^-]*$/, "", $2); print $2}' "$state/hosts")
  awk -v f="$first" -v n="$count" -v p="$prefix" -v c="$(nproc)" 'NR > f && NR <= f + n {
      r = NR - 1 - f; print "rank " r "=" p "-" $1 " slot=" (slot[$1]++ % c) }' \
    "$state/rank-hosts" >"$state/$name-rankfile"
  awk '{sub(/=/, " "); n[$3]++} END {for (x in n) print x " slots=" n[x]}' \
    "$state/$name-rankfile" >"$state/$name-hostfile"
  # The cluster's mpirun runs a subset of its ranks with --subset NP HOSTFILE RANKFILE.
  printf '#!/bin/sh\nexec "%s" --subset %s "%s" "%s" "$@"\n' "$state/mpirun" "$count" \
    "$state/$name-hostfile" "$state/$name-rankfile" >"$state/$name-mpirun"
  chmod +x "$state/$name-mpirun"
}

source "$root/bench/service_relay.sh"

service_pid=""
# service_start STATE PORT OUT [SERVE OPTIONS]: dfbwall serve on the wall hosts; waits for its
# address line.
service_start() {
  local state=$1 port=$2 out=$3
  shift 3
  "$state/wall-mpirun" "$dfbwall" serve --wall "$service_wall" --listen "0.0.0.0:$port" --offscreen \
    --timeout 30 --token "$service_token" --stats "$out.jsonl" --capture-root "$work" "$@" \
    >"$out.out" 2>"$out.err" &
  service_pid=$!
  local i
  for i in $(seq 300); do
    grep -q "wall service on" "$out.out" 2>/dev/null && return 0
    kill -0 "$service_pid" 2>/dev/null || break
    sleep 0.2
  done
  echo "bench: dfbwall serve did not start:" >&2
  cat "$out.out" "$out.err" >&2
  return 1
}
service_stop() {  # SIGUSR1 to mpirun (forwarded to the wall): a clean stop; then wait
  [ -n "$service_pid" ] || return 0
  kill -USR1 "$service_pid" 2>/dev/null || true
  local i
  for i in $(seq 100); do kill -0 "$service_pid" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$service_pid" 2>/dev/null && { echo "bench: serve did not stop on SIGUSR1" >&2; kill "$service_pid"; }
  wait "$service_pid" 2>/dev/null || true
  service_pid=""
}
service_cleanup() { service_stop; cluster_down_all; }

# service_cluster RATE: a cluster of 2 render hosts and the wall's hosts; sets service_state and
# service_address (wall1's).
service_cluster() {
  local up="$work/service-up-$1.txt" id
  "$root/scripts/cluster" up --id auto --holder $$ --build "$build" --wall "$service_wall" \
    --render-hosts 2 --rate "$1" >"$up"
  id=$(sed -n 's/^cluster \([0-9]*\):.*/\1/p' "$up")
  cluster_ids+=("$id")
  service_state=$(dirname "$(sed -n 's/^run: \([^ ]*\) .*/\1/p' "$up")")
  service_subset "$service_state" render 0 2
  service_subset "$service_state" wall 2 "$(($(wc -l <"$service_state/rank-hosts") - 2))"
  service_address=$(awk '$1 == "wall1" {print $3}' "$service_state/hosts")
}

# service_job NAME CODEC OPTIONS...: one job of the render hosts on the running service.
service_job() {
  local name=$1 codec=$2
  shift 2
  "$service_state/render-mpirun" "$dfbwall" --connect "$service_address:$service_port" \
    --token "$service_token" --codec "$codec" --quiet --timeout 300 --stats "$work/$name.json" "$@" ||
    echo "bench: service job $name failed; left out" >&2
}

fig_service() {
  local frames=10 reps=2 rframes=5
  [ $quick = 1 ] && frames=4 reps=1 rframes=3
  service_wall="$root/configs/walls/2x2-1080p-hosts.toml"
  service_token=$(od -An -tx1 -N16 /dev/urandom | tr -d ' \n')
  service_port=7000
  local gbit=125000000 mbit100=12500000 loadAtStart goals=() rows="" parts panels=()
  parts=" ${BENCH_SERVICE_PARTS:-route codecs relay curve jobs} "
  loadAtStart=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "== service: dfbwall serve on the wall hosts vs the single-job route; codecs at 100 Mbit/s; the relay's cost; load $loadAtStart"
  [ "$(id -u)" -eq 0 ] || { echo "bench: the service figure needs root (scripts/cluster)" >&2; return 1; }
  trap service_cleanup EXIT

  local dat="$work/svc-1g.dat" cdat="$work/svc-codecs.dat"
  if [[ "$parts" == *" route "* ]]; then
  # --- 1. 1 Gbit/s: route (one job over every host) vs service + job, pattern, uncompressed.
  service_cluster 1gbit
  local rep
  for rep in $(seq "$reps"); do  # interleaved: route, service, route, service
    "$service_state/mpirun" "$dfbwall" --wall "$service_wall" --offscreen --renderer pattern \
      --no-compress --frames "$frames" --quiet --timeout 300 --stats "$work/svc-route-$rep.json" ||
      echo "bench: route run $rep failed; left out" >&2
    service_start "$service_state" $service_port "$work/svc-serve-1g-$rep"
    service_job "svc-service-$rep" raw --renderer pattern --frames "$frames"
    service_stop
  done
  cluster_down_all

  local fps=() utils=()
  : >"$dat"
  local v
  for v in route service; do
    local files=("$work"/svc-$v-*.json) med mad cnt fr wire u
    read -r med mad cnt < <(pooled frame_ms "${files[@]}" | medmad)
    fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
    wire=$(pooled wall_bytes_sent "${files[@]}" | median)
    # Link utilisation: wire bytes per second over the two render hosts' uplinks.
    u=$(ratio_of wall_bytes_sent frame_ms "$(awk -v l=$gbit 'BEGIN {print 1000 / (2 * l)}')" "${files[@]}")
    u=$(awk -v u="$u" 'BEGIN {printf "%.3g", u}')
    fps+=("$fr")
    utils+=("$u")
    rows+="${rows:+,}
    {\"part\": \"1gbit\", \"variant\": \"$v\", \"renderer\": \"pattern\", \"codec\": \"raw\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr, \"wall_bytes_wire_per_frame\": $wire, \"link_utilisation\": $u}"
    echo "  1 Gbit/s, pattern raw, $v: $fr fps (median $med ms, MAD $mad), $wire bytes/frame, link utilisation $u"
    printf '"%s" %s %s\n' "$v" "$fr" "$u" >>"$dat"
  done
  local ratio
  ratio=$(awk -v a="${fps[1]}" -v b="${fps[0]}" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
  echo "  service/route frame rate: ${ratio}x"
  goals+=("service >= 0.9x route frame rate, pattern raw, 1 Gbit/s: ${ratio}x, $(awk -v a="$ratio" 'BEGIN {print (a >= 0.9) ? "met" : "missed"}')")
  goals+=("service link utilisation >= 0.8, pattern raw, 1 Gbit/s: ${utils[1]}, $(awk -v u="${utils[1]}" 'BEGIN {print (u >= 0.8) ? "met" : "missed"}')")
  panels+=("plot '$dat' using 2:xtic(1) title \"1 Gbit/s, pattern raw: fps\" lc rgb \"#3070b0\", '' using 0:3 axes x1y2 with points pt 7 ps 1.5 lc rgb \"#c03030\" title \"link utilisation\"")
  fi

  if [[ "$parts" == *" codecs "* ]]; then
  # --- 2. 100 Mbit/s: codecs, path tracer and scivis, captures of the last frame compared.
  service_cluster 100mbit
  service_start "$service_state" $service_port "$work/svc-serve-100m"
  local codecs=(jpeg:90 snappy raw) renderers=("pathtracer builtin:cornell" "scivis builtin:wavelet")
  local rv r sc c
  for rv in "${renderers[@]}"; do
    read -r r sc <<<"$rv"
    for c in "${codecs[@]}"; do
      rm -rf "$work/svc-cap-$r-${c%%:*}"
      service_job "svc-$r-${c%%:*}" "$c" --renderer "$r" --scene "$sc" --spp 1 --seed 7 \
        --frames "$rframes" --orbit $orbit --capture "$work/svc-cap-$r-${c%%:*}"
    done
  done
  service_stop
  cluster_down_all

  : >"$cdat"
  for rv in "${renderers[@]}"; do
    read -r r sc <<<"$rv"
    local jpegFps="" snappyFps="" jpegPsnr=""
    for c in "${codecs[@]}"; do
      local n=${c%%:*} med mad cnt fr wire raw psnr="null" worst="null" pairs=() d
      read -r med mad cnt < <(pooled frame_ms "$work/svc-$r-$n.json" | medmad)
      fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
      wire=$(pooled wall_bytes_sent "$work/svc-$r-$n.json" | median)
      raw=$(pooled wall_bytes_raw "$work/svc-$r-$n.json" | median)
      if [ "$n" != raw ]; then
        for d in "$work/svc-cap-$r-raw"/*/; do
          d=$(basename "$d")
          pairs+=("$work/svc-cap-$r-$n/$d/frame-$(printf '%06d' "$rframes").png"
                  "$work/svc-cap-$r-raw/$d/frame-$(printf '%06d' "$rframes").png")
        done
        if [ ${#pairs[@]} -gt 0 ] && read -r psnr worst < <("$build/bench/capture_psnr" "${pairs[@]}"); then
          [ "$psnr" = inf ] && psnr='"inf"'
        else
          psnr="null" worst="null"
          echo "bench: no PSNR for $r $c (captures missing?)" >&2
        fi
      fi
      rows+="${rows:+,}
    {\"part\": \"100mbit\", \"renderer\": \"$r\", \"scene\": \"$sc\", \"codec\": \"$c\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr, \"wall_bytes_wire_per_frame\": $wire, \"wall_bytes_raw_per_frame\": $raw, \"psnr_db_vs_raw\": $psnr, \"max_channel_error_vs_raw\": $worst}"
      echo "  100 Mbit/s, $r, $c: $fr fps (median $med ms, MAD $mad), $wire bytes/frame (raw $raw), PSNR vs raw ${psnr//\"/} dB (max error $worst)"
      printf '"%s %s" %s %s\n' "$r" "$n" "$fr" "$wire" >>"$cdat"
      [ "$n" = jpeg ] && jpegFps=$fr jpegPsnr=${psnr//\"/}
      [ "$n" = snappy ] && snappyFps=$fr
      if [ "$n" = snappy ] && [ "$psnr" != '"inf"' ]; then
        goals+=("snappy lossless, $r: PSNR vs raw ${psnr//\"/} dB, missed")
      fi
    done
    local jr
    jr=$(awk -v a="$jpegFps" -v b="$snappyFps" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
    echo "  $r: jpeg:90/snappy frame rate ${jr}x at ${jpegPsnr} dB"
    goals+=("jpeg:90 >= 3x snappy frame rate at >= 40 dB, $r, 100 Mbit/s: ${jr}x at ${jpegPsnr} dB, $(awk -v a="$jr" -v p="$jpegPsnr" 'BEGIN {print (a >= 3 && p != "null" && p + 0 >= 40) ? "met" : "missed"}')")
  done

  panels+=("set logscale y; set yrange [*:*]; set ylabel \"frames per second (log)\"; set y2label \"MB per frame (log)\"; set logscale y2; set y2range [*:*]; plot '$cdat' using 2:xtic(1) title \"100 Mbit/s: fps\" lc rgb \"#3070b0\", '' using 0:(\$3 / 1e6) axes x1y2 with points pt 7 ps 1.5 lc rgb \"#c03030\" title \"MB per frame\"; unset logscale y; unset logscale y2")
  fi

  [[ "$parts" != *" relay "* ]] || service_relay_part

  if [[ "$parts" == *" curve "* ]]; then
  # --- 4. 1 Gbit/s: the same jobs on a PLAIN wall and on a CURVE wall, interleaved.
  service_cluster 1gbit
  rm -rf "$work/svc-keys"
  "$dfbwall" keygen "$work/svc-keys" >/dev/null
  local sec serveKey=() jobKey=()
  for rep in $(seq "$reps"); do
    for sec in plain curve; do
      serveKey=() jobKey=()
      [ $sec = plain ] || serveKey=(--curve "$work/svc-keys") jobKey=(--server-key "$work/svc-keys/wall-public.key")
      service_start "$service_state" $service_port "$work/svc-serve-$sec-$rep" ${serveKey[@]+"${serveKey[@]}"}
      service_job "svc-sec-$sec-pattern-$rep" raw --renderer pattern --frames "$frames" \
        ${jobKey[@]+"${jobKey[@]}"}
      service_job "svc-sec-$sec-pathtracer-$rep" snappy --renderer pathtracer --scene builtin:cornell \
        --spp 1 --seed 7 --frames "$rframes" ${jobKey[@]+"${jobKey[@]}"}
      service_stop
    done
  done
  cluster_down_all
  local r
  for r in pattern pathtracer; do
    local plainFps="" curveFps=""
    for sec in plain curve; do
      local files=("$work"/svc-sec-$sec-$r-*.json) med mad cnt fr wire
      read -r med mad cnt < <(pooled frame_ms "${files[@]}" | medmad)
      fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
      wire=$(pooled wall_bytes_sent "${files[@]}" | median)
      rows+="${rows:+,}
    {\"part\": \"curve\", \"variant\": \"$sec\", \"renderer\": \"$r\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr, \"wall_bytes_wire_per_frame\": $wire}"
      echo "  1 Gbit/s, $r, $sec: $fr fps (median $med ms, MAD $mad), $wire bytes/frame"
      [ $sec = plain ] && plainFps=$fr || curveFps=$fr
    done
    local cr
    cr=$(awk -v a="$curveFps" -v b="$plainFps" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
    echo "  $r: CURVE/PLAIN frame rate ${cr}x"
    goals+=("CURVE >= 0.9x PLAIN frame rate, $r, 1 Gbit/s: ${cr}x, $(awk -v a="$cr" 'BEGIN {print (a >= 0.9) ? "met" : "missed"}')")
  done
  fi

  if [[ "$parts" == *" jobs "* ]]; then
  # --- 5. 1 Gbit/s: two pattern jobs at once, each in half of the wall, vs one alone.
  service_cluster 1gbit
  local left=0,0,1920,2160 right=1920,0,1920,2160 half=$((1920 * 2160)) together
  for rep in $(seq "$reps"); do  # interleaved: alone, together, alone, together
    service_start "$service_state" $service_port "$work/svc-serve-jobs-$rep"
    service_job "svc-jobs-alone-$rep" raw --renderer pattern --frames "$frames" --window "$left"
    service_job "svc-jobs-left-$rep" raw --renderer pattern --frames "$frames" --window "$left" &
    together=$!
    service_job "svc-jobs-right-$rep" raw --renderer pattern --frames "$frames" --window "$right"
    wait "$together"
    service_stop
  done
  cluster_down_all
  local v pps=() sum=0
  for v in alone left right; do
    local files=("$work"/svc-jobs-$v-*.json) med mad cnt fr p
    read -r med mad cnt < <(pooled frame_ms "${files[@]}" | medmad)
    fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
    p=$(awk -v f="$fr" -v h="$half" 'BEGIN {printf "%.4g", f * h}')
    rows+="${rows:+,}
    {\"part\": \"jobs\", \"variant\": \"$v\", \"renderer\": \"pattern\", \"codec\": \"raw\", \"window\": \"$([ $v = right ] && echo "$right" || echo "$left")\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr, \"pixels_per_second\": $p}"
    echo "  1 Gbit/s, pattern raw, $v: $fr fps (median $med ms, MAD $mad), $p pixels/s"
    [ $v = alone ] && pps=("$p") || sum=$(awk -v a="$sum" -v b="$p" 'BEGIN {print a + b}')
  done
  local jr
  jr=$(awk -v a="$sum" -v b="${pps[0]}" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
  echo "  two jobs together / one alone, pixels per second: ${jr}x"
  goals+=("two pattern jobs together >= 0.9x the pixels per second of one, 1 Gbit/s: ${jr}x, $(awk -v a="$jr" 'BEGIN {print (a >= 0.9) ? "met" : "missed"}')")
  fi

  goals_json ${goals[@]+"${goals[@]}"}
  cat >"$results/service.json" <<EOF
{"figure": "service", "machine": $machine, "load_average_at_start": "$loadAtStart", "load_average_at_end": "$(cut -d' ' -f1-3 /proc/loadavg)",
 "setup": {"wall": "2x2 x 1920x1080 (3840x2160) on hosts wall1 (top row) and wall2 (bottom row), one process per display",
           "render_hosts": 2, "render_ranks_per_host": 1, "links": "tc tbf each way per host (scripts/cluster): 1gbit for part 1, 100mbit for part 2",
           "route": "one mpirun over every host: dfbwall --wall ... --renderer pattern --no-compress",
           "service": "dfbwall serve on the wall hosts only (an mpirun with a wall-only hostfile and rankfile), job: an mpirun with a render-only one, --connect wall1:$service_port",
           "frames_per_run": {"pattern": $frames, "pathtracer, scivis": $rframes}, "runs_part_1": $reps, "spp": 1, "seed": 7, "orbit_degrees_per_frame": $orbit,
           "link_utilisation": "wall_bytes_sent per second / (2 render hosts x 125e6 B/s)",
           "relay": "part 3: the same pattern raw job straight to the wall (render hosts on the wall's network) and through dfbwall relay on gateway1 (render hosts on a network of their own that reaches only the gateway: scripts/cluster --gateway-hosts 1), with 2 and 1 render hosts; every link, the gateway's two legs too, 1 Gbit/s each way; binding link utilisation: wall_bytes_sent per second over the render hosts' uplinks (direct) or the gateway's one leg (relay)",
           "psnr": "RGB, pooled over the 4 displays' captures of the last frame, against the raw job's captures of the same frame"},
 "goals": [$goals_json],
 "results": [$rows
 ]}
EOF
  [ ${#panels[@]} -gt 0 ] || { trap - EXIT; return 0; }
  local plot panel
  plot="set multiplot layout 1,${#panels[@]} title \"The wall as a service, 2x2 1080p wall, emulated hosts (median over the frames)\"
set style data histogram; set style fill solid 0.6; set key top right; set xtics rotate by -30 font \",9\"
set y2tics; set ytics nomirror"
  for panel in "${panels[@]}"; do
    plot+=$'\n'"set ylabel \"frames per second\"; set yrange [0:*]; set y2label \"link utilisation\"; set y2range [0:1.05]; $panel"
  done
  gnuplot -e "set terminal pngcairo size $((600 * ${#panels[@]})),520 noenhanced; set output '$results/service.png'" \
    <(printf '%s\nunset multiplot\n' "$plot")
  trap - EXIT
}
