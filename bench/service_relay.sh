# Part 3 of the `service` figure (sourced by bench/service.sh, which fig_service calls it from;
# uses scripts/bench's helpers and fig_service's variables: rows, goals, panels, frames, reps):
# what `dfbwall relay` costs at 1 Gbit/s. The same job (pattern, 3840x2160 uncompressed, --codec
# raw) on the 2x2 1080p wall's hosts:
#  - direct: render hosts on the wall's network, --connect wall1 (as part 1's service job);
#  - relay:  render hosts on a network of their own (scripts/cluster --gateway-hosts 1) that
#            reaches only gateway1, which runs `dfbwall relay`; --connect gateway1.
# Each with 2 render hosts (one rank each) and with 1, interleaved (direct, relay, direct, ...).
# Every link is 1 Gbit/s each way, the gateway's two legs too: with 2 render hosts the relay's
# one leg carries what two uplinks carry directly (the cost of one gateway); with 1 render host
# both are bound by that host's uplink (the cost of the hop itself).

# relay_run VARIANT CLUSTER_ID STATE HOSTS REP: serve (and the relay), one job, stop them.
relay_run() {
  local variant=$1 id=$2 state=$3 n=$4 rep=$5 wallAddress target out
  out="$work/svc-relay-$variant-$n-$rep"
  wallAddress=$(awk '$1 == "wall1" {print $3}' "$state/hosts")
  "$root/scripts/cluster" mpirun-hosts wall1 wall2 --id "$id" -- "$dfbwall" serve \
    --wall "$service_wall" --listen "0.0.0.0:$service_port" --offscreen --timeout 30 \
    --token "$service_token" >"$out-serve.out" 2>"$out-serve.err" &
  service_pid=$!
  local relayPid="" i
  for i in $(seq 300); do grep -q "wall service on" "$out-serve.out" 2>/dev/null && break; sleep 0.2; done
  target=$wallAddress:$service_port
  if [ "$variant" = relay ]; then
    target=$(awk '$1 == "gateway1" {print $5}' "$state/hosts"):$((service_port + 1))
    "$root/scripts/cluster" exec gateway1 --id "$id" -- "$dfbwall" relay --listen "$target" \
      --wall "$wallAddress:$service_port" --token "$service_token" --timeout 30 --stats "$out-relay.jsonl" \
      >"$out-relay.out" 2>"$out-relay.err" &
    relayPid=$!
    for i in $(seq 100); do grep -q "relay on" "$out-relay.out" 2>/dev/null && break; sleep 0.1; done
  fi
  local hosts=(render1)
  [ "$n" -eq 1 ] || hosts=(render1 render2)
  "$root/scripts/cluster" mpirun-hosts "${hosts[@]}" --id "$id" -- "$dfbwall" --connect "$target" \
    --token "$service_token" --codec raw --renderer pattern --frames "$frames" --quiet \
    --timeout 300 --stats "$out.json" >"$out.log" 2>&1 ||
    { echo "bench: relay figure, $variant with $n render hosts, run $rep failed; left out" >&2; rm -f "$out.json"; }
  if [ -n "$relayPid" ]; then
    # The relay's CPU over its whole life (idle before and after the job included), in ticks.
    awk '{print $14 + $15}' "/proc/$relayPid/stat" >"$out-relay.ticks" 2>/dev/null || true
    kill -USR1 "$relayPid" 2>/dev/null || true
    wait "$relayPid" 2>/dev/null || true
  fi
  service_stop
}

service_relay_part() {
  local upD="$work/relay-up-direct.txt" upR="$work/relay-up-gateway.txt" idD idR stateD stateR
  "$root/scripts/cluster" up --id auto --holder $$ --build "$build" --wall "$service_wall" \
    --render-hosts 2 --rate 1gbit >"$upD"
  idD=$(sed -n 's/^cluster \([0-9]*\):.*/\1/p' "$upD")
  cluster_ids+=("$idD")
  "$root/scripts/cluster" up --id auto --holder $$ --build "$build" --wall "$service_wall" \
    --render-hosts 2 --gateway-hosts 1 --rate 1gbit >"$upR"
  idR=$(sed -n 's/^cluster \([0-9]*\):.*/\1/p' "$upR")
  cluster_ids+=("$idR")
  stateD=$(dirname "$(sed -n 's/^run: \([^ ]*\) .*/\1/p' "$upD")")
  stateR=$(dirname "$(sed -n 's/^run: \([^ ]*\) .*/\1/p' "$upR")")
  local rep n
  for rep in $(seq "$reps"); do
    for n in 2 1; do
      relay_run direct "$idD" "$stateD" "$n" "$rep"
      relay_run relay "$idR" "$stateR" "$n" "$rep"
    done
  done
  cluster_down_all

  local rdat="$work/svc-relay.dat" v f files med mad cnt fr wire u links ratio
  : >"$rdat"
  for n in 2 1; do
    local fpsOf=()
    for v in direct relay; do
      files=()
      for f in "$work"/svc-relay-$v-$n-*.json; do [ -f "$f" ] && files+=("$f"); done
      [ ${#files[@]} -gt 0 ] || { fpsOf+=(0); continue; }
      read -r med mad cnt < <(pooled frame_ms "${files[@]}" | medmad)
      fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
      wire=$(pooled wall_bytes_sent "${files[@]}" | median)
      # Utilisation of the links that bind: the render hosts' uplinks, or the gateway's one leg.
      links=$n
      [ "$v" = direct ] || links=1
      u=$(ratio_of wall_bytes_sent frame_ms "$(awk -v l=125000000 -v k="$links" 'BEGIN {print 1000 / (k * l)}')" "${files[@]}")
      u=$(awk -v u="$u" 'BEGIN {printf "%.3g", u}')
      fpsOf+=("$fr")
      rows+="${rows:+,}
    {\"part\": \"relay\", \"variant\": \"$v\", \"render_hosts\": $n, \"renderer\": \"pattern\", \"codec\": \"raw\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr, \"wall_bytes_wire_per_frame\": $wire, \"binding_links\": $links, \"binding_link_utilisation\": $u}"
      echo "  1 Gbit/s, pattern raw, $n render host(s), $v: $fr fps (median $med ms, MAD $mad), $wire bytes/frame, utilisation of the $links binding link(s) $u"
      local cpu="null"
      if [ "$v" = relay ]; then
        # CPU ms of the relay per frame forwarded, over the runs of this variant.
        cpu=$(cat "$work"/svc-relay-relay-$n-*-relay.ticks 2>/dev/null | awk -v t="$(getconf CLK_TCK)" \
          -v f="$(( ${#files[@]} * frames ))" '{s += $1} END {printf "%.3g", (f > 0) ? s * 1000 / t / f : 0}')
        echo "    relay CPU: $cpu ms per frame (33 MB)"
      fi
      rows="${rows%\}}, \"relay_cpu_ms_per_frame\": $cpu}"
      printf '"%s, %s host%s" %s %s\n' "$v" "$n" "$([ "$n" -eq 1 ] || echo s)" "$fr" "$u" >>"$rdat"
    done
    ratio=$(awk -v a="${fpsOf[1]}" -v b="${fpsOf[0]}" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
    rows+=",
    {\"part\": \"relay\", \"render_hosts\": $n, \"relay_over_direct_fps\": $ratio}"
    echo "  relay/direct frame rate, $n render host(s): ${ratio}x"
    if [ "$n" -eq 1 ]; then
      goals+=("relay >= 0.9x direct frame rate, 1 render host, pattern raw, 1 Gbit/s: ${ratio}x, $(awk -v a="$ratio" 'BEGIN {print (a >= 0.9) ? "met" : "missed"}')")
    fi
  done
  panels+=("set title \"relay vs direct, 1 Gbit/s, pattern raw\"; plot '$rdat' using 2:xtic(1) title \"fps\" lc rgb \"#3070b0\", '' using 0:3 axes x1y2 with points pt 7 ps 1.5 lc rgb \"#c03030\" title \"binding link utilisation\"; unset title")
}
