// The operator page: polls the daemon's state once a second and shows it.
// Every string from the daemon goes in as text (textContent), never as
// markup. Nothing here sends anything that changes the cell: GET only.
"use strict";

const POLL_MS = 1000;
const token = new URLSearchParams(window.location.search).get("token");
let openSeq = null;
let lastListKey = "";
let plansBySeq = new Map();

function withToken(path) {
  return token ? path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token) : path;
}

async function getJson(path) {
  const headers = token ? { Authorization: "Bearer " + token } : {};
  const response = await fetch(path, { headers, cache: "no-store" });
  if (!response.ok) {
    throw new Error(path + ": " + response.status + " " + (await response.text()).trim());
  }
  return response.json();
}

function el(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined && text !== null) node.textContent = String(text);
  return node;
}

function clock(us) {
  return new Date(us / 1000).toLocaleTimeString([], { hour12: false });
}

function ms(value) {
  return value >= 100 ? value.toFixed(0) + " ms" : value.toFixed(1) + " ms";
}

function size(bytes) {
  return bytes >= 1e9 ? (bytes / 1e9).toFixed(1) + " GB" : (bytes / 1e6).toFixed(1) + " MB";
}

function showCell(state) {
  const links = document.getElementById("links");
  links.replaceChildren();
  for (const link of state.links) {
    const item = el("li", null, link.link + ": " + link.connections + " connected");
    for (const peer of state.peers.filter((p) => p.link === link.link)) {
      item.append(el("div", "dim", peer.name + " from " + peer.address + " since " + clock(peer.since_us)));
    }
    links.append(item);
  }
  const frame = state.last_frame;
  document.getElementById("frame").textContent = frame
    ? "frame " + frame.frame_id + " from " + frame.camera + " at " + clock(frame.received_us) + ", " +
      frame.points.toLocaleString() + " points, " + Math.max(0, (state.now_us - frame.received_us) / 1e6).toFixed(0) + " s ago"
    : "none yet";
  const q = state.queue;
  document.getElementById("queue").textContent =
    q.jobs + " of " + q.depth + " plans queued or running; " + q.frames_awaited + " frames awaited";
  const records = state.records;
  document.getElementById("records").textContent = records
    ? "records: " + records.count + " (" + size(records.bytes) + " of " + size(records.max_bytes) + ")"
    : "";
}

function planRow(plan) {
  const button = el("button", "plan");
  button.type = "button";
  button.dataset.seq = plan.seq;
  button.dataset.outcome = plan.outcome;
  button.append(el("span", "time", clock(plan.time_us)));
  button.append(el("span", "request", "#" + plan.request_id));
  const what = el("span", "what");
  what.append(el("span", "outcome", plan.outcome === "planned" ? "PLANNED" : "REFUSED"));
  what.append(document.createTextNode(" " + plan.joint + ", " + plan.seams + (plan.seams === 1 ? " seam" : " seams")));
  if (plan.rule) {
    what.append(document.createTextNode(" "));
    what.append(el("span", "rule", plan.rule));
  }
  button.append(what);
  const details = [];
  if (plan.reason) details.push(plan.reason);
  details.push("plan " + ms(plan.plan_ms));
  if (plan.frame_id !== null) details.push("frame " + plan.frame_id);
  if (plan.record) details.push("record " + plan.record);
  button.append(el("span", "line2", details.join(" · ")));
  button.addEventListener("click", () => openPlan(plan.seq));
  const item = el("li");
  item.append(button);
  return item;
}

function showPlans(plans) {
  plansBySeq = new Map(plans.map((p) => [p.seq, p]));
  const key = JSON.stringify(plans);
  if (key === lastListKey) return;
  lastListKey = key;
  const focused = document.activeElement && document.activeElement.dataset ? document.activeElement.dataset.seq : null;
  const list = document.getElementById("plans");
  list.replaceChildren(...plans.map(planRow));
  document.getElementById("no-plans").hidden = plans.length > 0;
  if (focused) {
    const again = list.querySelector('button[data-seq="' + CSS.escape(focused) + '"]');
    if (again) again.focus();
  }
  if (openSeq !== null) {
    const open = plansBySeq.get(openSeq);
    if (open && open.pictures && document.getElementById("camera-figure").hidden) openPlan(openSeq);
  }
}

function row(table, cells) {
  const tr = el("tr");
  for (const cell of cells) tr.append(el("td", null, cell));
  table.append(tr);
}

function fixed(value, digits) {
  return value === null || value === undefined ? "–" : Number(value).toFixed(digits);
}

async function openPlan(seq) {
  let answer;
  try {
    answer = await getJson("/api/plans/" + seq);
  } catch (error) {
    document.getElementById("status").textContent = String(error.message);
    return;
  }
  openSeq = seq;
  const plan = answer.plan;
  // The plan takes the screen: its pictures are what the operator came for.
  document.getElementById("list").hidden = true;
  document.getElementById("cell").hidden = true;
  document.getElementById("detail").hidden = false;
  document.getElementById("detail-title").textContent =
    "Request #" + plan.request_id + " at " + clock(plan.time_us) + ": " + plan.joint + ", " +
    (plan.outcome === "planned" ? "planned, " + plan.seams + (plan.seams === 1 ? " seam" : " seams") : "refused (" + plan.outcome + ")");
  const reason = document.getElementById("detail-reason");
  reason.replaceChildren();
  if (plan.rule) reason.append(el("span", "rule", plan.rule), document.createTextNode(": "));
  if (plan.reason) reason.append(document.createTextNode(plan.reason));
  document.getElementById("detail-record").textContent = plan.record ? "record " + plan.record + " (weldseam replay)" : "";
  const camera = document.getElementById("camera-view");
  const sections = document.getElementById("sections");
  const profile = document.getElementById("profile");
  document.getElementById("camera-figure").hidden = !plan.pictures;
  document.getElementById("sections-figure").hidden = !plan.sections;
  document.getElementById("profile-figure").hidden = !plan.profile;
  document.getElementById("detail-no-pictures").hidden = plan.pictures;
  if (plan.pictures) camera.src = withToken("/api/plans/" + seq + "/camera.png");
  if (plan.sections) sections.src = withToken("/api/plans/" + seq + "/sections.png");
  if (plan.profile) profile.src = withToken("/api/plans/" + seq + "/profile.png");
  showProcess(answer.seams || []);

  const figures = document.querySelector("#figures tbody");
  figures.replaceChildren();
  row(figures, ["frame", plan.frame_id === null ? "–" : plan.frame_id + (plan.camera ? " from " + plan.camera : "")]);
  row(figures, ["points", plan.points === null ? "–" : plan.points.toLocaleString()]);
  row(figures, ["plan time", ms(plan.plan_ms)]);
  row(figures, ["request to reply", ms(plan.latency_ms)]);
  const waypoints = document.querySelector("#waypoints tbody");
  waypoints.replaceChildren();
  const result = answer.result;
  if (result) {
    result.seams.forEach((seam, k) => {
      const label = "seam " + (k + 1) + " ";
      row(figures, [label + "length", fixed(seam.length_mm, 1) + " mm"]);
      row(figures, [label + "edge fits rms", fixed(seam.edge_fit_rms_mm[0], 3) + " / " + fixed(seam.edge_fit_rms_mm[1], 3) + " mm"]);
      if (seam.quality) {
        const q = seam.quality;
        if (q.gap_mm) row(figures, [label + "gap", fixed(q.gap_mm.min, 2) + " to " + fixed(q.gap_mm.max, 2) + " mm"]);
        if (q.misalignment_mm !== null && q.misalignment_mm !== undefined) row(figures, [label + "high-low", fixed(q.misalignment_mm, 2) + " mm"]);
        row(figures, [label + "position ±", fixed(q.uncertainty_across_mm, 2) + " mm (1 sigma)"]);
      }
      for (const warning of seam.warnings) row(figures, [label + "warning " + (warning.rule || warning.gate), warning.message]);
      seam.waypoints.forEach((w, i) => {
        row(waypoints, [String(k + 1), String(i), fixed(w.xyz[0], 2), fixed(w.xyz[1], 2), fixed(w.xyz[2], 2),
          fixed(w.rpy_deg[0], 2), fixed(w.rpy_deg[1], 2), fixed(w.rpy_deg[2], 2)]);
      });
    });
    for (const unplanned of result.unplanned) {
      row(figures, ["not planned: " + (unplanned.joint || "a joint"), (unplanned.refusal.rule || "") + " " + unplanned.refusal.message]);
    }
  }
  document.getElementById("close").focus();
}

// Per seam, what the procedure made of it: its passes, and each stretch
// not welded with the rule that cut it and why, so the operator reads
// the reason beside the profile's shaded stretch.
function showProcess(seams) {
  const box = document.getElementById("process-seams");
  box.replaceChildren();
  let any = false;
  seams.forEach((seam, k) => {
    const p = seam.process;
    if (!p) return;
    any = true;
    const block = el("div", "seam-process");
    block.append(el("h4", null, "seam " + (k + 1) + ": " + p.procedure + ", " + p.welded + " of " + p.waypoints + " waypoints welded"));
    for (const pass of p.passes) {
      const speed = pass.speed_mm_s[0] === pass.speed_mm_s[1]
        ? fixed(pass.speed_mm_s[0], 1)
        : fixed(pass.speed_mm_s[0], 1) + " to " + fixed(pass.speed_mm_s[1], 1);
      const weave = pass.weave_mm > 0 ? ", weave up to ±" + fixed(pass.weave_mm, 1) + " mm" : "";
      block.append(el("p", "pass", pass.kind + " pass (layer " + pass.layer + ", bead " + pass.bead + ") at " +
        pass.waypoints + " waypoints, " + speed + " mm/s" + weave));
    }
    for (const cut of p.cut) {
      const line = el("p", "cut");
      line.append(document.createTextNode("not welded: waypoints " + cut.first + " to " + cut.last + ", "));
      line.append(el("span", "rule", cut.rule));
      line.append(document.createTextNode(": " + cut.reason));
      if (cut.contact_camera_mm) {
        const c = cut.contact_camera_mm;
        line.append(document.createTextNode(" (torch touches at " + fixed(c[0], 1) + ", " + fixed(c[1], 1) + ", " + fixed(c[2], 1) + " mm, camera frame)"));
      }
      block.append(line);
    }
    if (p.re_angled.length > 0) {
      const runs = p.re_angled.map((r) => (r[0] === r[1] ? String(r[0]) : r[0] + " to " + r[1])).join(", ");
      block.append(el("p", "re-angled", "torch re-angled to clear the workpiece at waypoints " + runs));
    }
    box.append(block);
  });
  document.getElementById("process").hidden = !any;
}

function closePlan() {
  const seq = openSeq;
  openSeq = null;
  document.getElementById("detail").hidden = true;
  document.getElementById("cell").hidden = false;
  document.getElementById("list").hidden = false;
  const button = document.querySelector('#plans button[data-seq="' + seq + '"]') || document.querySelector("#plans button");
  if (button) button.focus();
}

document.getElementById("close").addEventListener("click", closePlan);
document.addEventListener("keydown", (event) => {
  if (event.key === "Escape" && openSeq !== null) {
    closePlan();
    return;
  }
  if (openSeq !== null || (event.key !== "ArrowDown" && event.key !== "ArrowUp")) return;
  const buttons = Array.from(document.querySelectorAll("#plans button"));
  if (buttons.length === 0) return;
  const at = buttons.indexOf(document.activeElement);
  const next = event.key === "ArrowDown" ? Math.min(at + 1, buttons.length - 1) : Math.max(at - 1, 0);
  buttons[at < 0 ? 0 : next].focus();
  event.preventDefault();
});

async function poll() {
  const status = document.getElementById("status");
  try {
    const state = await getJson("/api/state");
    status.textContent = state.server + ", up " + Math.round(state.uptime_ms / 1000) + " s, " +
      state.frames_received + " frames received, " + state.plans_done + " planned";
    status.classList.remove("down");
    showCell(state);
    showPlans(state.plans);
  } catch (error) {
    status.textContent = "no answer from the daemon: " + String(error.message);
    status.classList.add("down");
  }
  window.setTimeout(poll, POLL_MS);
}

poll();
