// shadelab experiment runner: "bump or dimple?" with shaded stimuli turned to each rotation.
//
// Plain JavaScript, no libraries, no network: everything it needs is in this folder (the design
// is embedded in index.html, as in design.json). The flow, one function per screen:
//
//   instructions (consent, participant id) -> calibration (optional) -> practice -> test -> end
//
// Each trial: a fixation cross, then the image until a key (design.keys) is pressed; the
// reaction time is measured from the frame the image was first drawn. The end screen offers
// the responses as a CSV download and shows them in <pre id="results">.
//
// URL parameters:
//   ?participant=ID                 fills in the participant id
//   ?simulate=tilt:T,kappa:K,convex:C,lapse:L,seed:S
//                                   pilot mode: answers every trial at once from the observer
//                                   model (tilt and kappa required; convex 0.5, lapse 0 and
//                                   seed 1 by default) and shows the CSV
//   ?preview=trial|calibration      shows that screen as a participant sees it (nothing is
//                                   recorded), to check the display
//
// To adapt it: the texts are in the screen functions below; the design (stimulus, rotations,
// repeats, keys, timing) comes from `shadelab experiment`, not from here.
(function () {
  'use strict';

  const design = JSON.parse(document.getElementById('design').textContent);
  const app = document.getElementById('app');
  const url = new URLSearchParams(window.location.search);
  const HEADER = design.model.responses_csv; // ...,image,design_hash
  const CARD_WIDTH_CM = 8.56; // ISO/IEC 7810 ID-1 (credit card): 85.60 mm x 53.98 mm
  const CARD_ASPECT = 53.98 / 85.6;

  // The session: who, how the display was scaled, and the responses so far.
  const session = {
    participant: '',
    ppdScreen: design.display.ppd, // CSS pixels per degree; the images' own ppd until calibrated
    calibrated: false,
    pxPerCm: null,
    rows: [],
  };

  // ---- Small helpers -------------------------------------------------------------------

  // An element with attributes and children (text is always set as text, never as HTML).
  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === 'text') node.textContent = v;
      else if (k === 'style') Object.assign(node.style, v);
      else if (k.startsWith('on')) node.addEventListener(k.slice(2), v);
      else node.setAttribute(k, v);
    }
    for (const c of children) node.append(c);
    return node;
  }

  function show(...nodes) {
    app.className = '';
    app.replaceChildren(...nodes);
  }

  // A problem the page cannot go on from (bad URL parameters): said on the page.
  function fail(text) {
    show(el('h1', { text: 'This page cannot start' }),
      el('div', { id: 'message', class: 'message', text: text }));
  }

  function key(k) {
    return el('kbd', { text: k.toUpperCase() });
  }

  function wait(ms) {
    return new Promise((resolve) => setTimeout(resolve, ms));
  }

  // Resolves with the next key press among `keys` (lower case), and when it happened.
  function nextKey(keys) {
    return new Promise((resolve) => {
      function onKey(e) {
        const k = (e.key || '').toLowerCase();
        if (keys.includes(k) && !e.repeat) {
          window.removeEventListener('keydown', onKey);
          e.preventDefault();
          resolve({ key: k, time: performance.now() });
        }
      }
      window.addEventListener('keydown', onKey);
    });
  }

  // One CSV field, quoted when it holds a comma, a quote or a line break.
  function csvField(v) {
    const s = String(v);
    return /[",\r\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
  }

  function csv(rows) {
    const fields = HEADER.split(',');
    return [HEADER].concat(rows.map((r) => fields.map((f) => csvField(r[f])).join(','))).join('\n') + '\n';
  }

  // ---- The observer model (pilot mode) ------------------------------------------------

  // mulberry32 (Tommy Ettinger's 32-bit generator): a seeded uniform in [0, 1).
  function mulberry32(seed) {
    let a = seed >>> 0;
    return function () {
      a = (a + 0x6d2b79f5) >>> 0;
      let t = a;
      t = Math.imul(t ^ (t >>> 15), t | 1);
      t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
      return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
    };
  }

  // P(convex | theta) = lapse/2 + (1 - lapse) * pi*vM(theta; mu, kappa) /
  //                     (pi*vM(theta; mu, kappa) + (1 - pi)*vM(theta + 180; mu, kappa)),
  // with vM(x; mu, kappa) taken as exp(kappa cos(x - mu)): the von Mises normaliser cancels.
  // theta and mu in degrees, tilt convention (0 = up, +90 = left).
  function pConvex(theta, m) {
    const rad = Math.PI / 180;
    const lit = m.convex * Math.exp(m.kappa * Math.cos((theta - m.tilt) * rad));
    const opposite = (1 - m.convex) * Math.exp(m.kappa * Math.cos((theta + 180 - m.tilt) * rad));
    return m.lapse / 2 + (1 - m.lapse) * lit / (lit + opposite);
  }

  // Parses `tilt:T,kappa:K,convex:C,lapse:L,seed:S`; throws a one-line message when bad.
  function parseSimulate(text) {
    const ranges = {
      tilt: [-360, 360, 'a number of degrees from -360 to 360'],
      kappa: [0, 100, 'a number from 0 to 100'],
      convex: [0, 1, 'a probability from 0 to 1'],
      lapse: [0, 1, 'a probability from 0 to 1'],
      seed: [0, 4294967295, 'a whole number from 0 to 4294967295'],
    };
    const model = { convex: 0.5, lapse: 0, seed: 1 };
    const given = new Set();
    for (const part of text.split(',')) {
      const m = /^\s*([a-z]+)\s*:\s*([^:]*?)\s*$/.exec(part);
      if (!m) throw new Error(`simulate: '${part}' is not NAME:VALUE (e.g. tilt:26)`);
      const [, name, value] = m;
      if (!(name in ranges)) {
        throw new Error(`simulate: unknown parameter '${name}' (use tilt, kappa, convex, lapse, seed)`);
      }
      if (given.has(name)) throw new Error(`simulate: '${name}' is given twice`);
      const [lo, hi, what] = ranges[name];
      const v = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(value) ? Number(value) : NaN;
      if (!(v >= lo && v <= hi) || (name === 'seed' && !Number.isInteger(v))) {
        throw new Error(`simulate: ${name} '${value}' must be ${what}`);
      }
      model[name] = v;
      given.add(name);
    }
    for (const needed of ['tilt', 'kappa']) {
      if (!given.has(needed)) {
        throw new Error(`simulate: give ${needed} (e.g. simulate=tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1)`);
      }
    }
    return model;
  }

  // Answers every trial from the model, then shows the end screen.
  function simulate(model) {
    const random = mulberry32(model.seed);
    session.participant = url.get('participant') || `simulated-seed${model.seed}`;
    for (const t of design.trials) {
      const convex = random() < pConvex(t.rotation_deg, model);
      record(t, convex ? 'convex' : 'concave', Math.round(400 + 400 * random()),
        convex ? design.keys.convex : design.keys.concave);
    }
    end(`Simulated observer: prior light tilt ${model.tilt} deg, kappa ${model.kappa}, ` +
      `convexity prior ${model.convex}, lapse ${model.lapse}, seed ${model.seed}.`);
  }

  function record(trial, response, rt, pressed) {
    session.rows.push({
      participant: session.participant,
      trial: trial.trial,
      block: trial.block,
      stimulus: design.stimulus,
      rotation_deg: trial.rotation_deg,
      response: response,
      rt_ms: rt,
      key: pressed,
      image: trial.image,
      design_hash: design.design_hash, // tells these rows from an earlier design's
    });
  }

  // ---- Images ---------------------------------------------------------------------------

  // Every image, loaded before the first trial so that none is drawn late.
  const images = {};
  function preload() {
    return Promise.all(design.images.map((entry) => new Promise((resolve, reject) => {
      const img = new Image();
      img.onload = () => resolve();
      img.onerror = () => reject(new Error(`cannot load ${entry.file}`));
      img.src = entry.file;
      img.alt = '';
      images[entry.file] = img;
    })));
  }

  // The image of `file` at the design's size in degrees on this display.
  function sized(file) {
    const img = images[file];
    const [h, w] = design.display.visual_size;
    img.style.width = `${w * session.ppdScreen}px`;
    img.style.height = `${h * session.ppdScreen}px`;
    return img;
  }

  // ---- Screens --------------------------------------------------------------------------

  function instructions() {
    const id = el('input', { type: 'text', id: 'participant', autocomplete: 'off',
      value: url.get('participant') || '' });
    const agree = el('input', { type: 'checkbox', id: 'consent' });
    const problem = el('p', { class: 'message', style: { display: 'none' } });
    const k = design.keys;
    show(
      el('h1', { text: 'Bump or dimple?' }),
      el('p', { text: 'In this experiment you will see a shaded disc in the middle of the screen. ' +
        'It can look like a bump (bulging towards you) or like a dimple (a hollow). ' +
        'There are no right or wrong answers: we want to know how it looks to you.' }),
      el('p', {}, 'Look at the cross in the middle; when the disc appears, press ', key(k.convex),
        ' if it looks like a bump or ', key(k.concave), ' if it looks like a dimple. ',
        'Answer quickly, by your first impression.'),
      el('p', { text: `There are ${design.practice_trials} practice trials, then ${design.test_trials} ` +
        'trials, which take about ' + Math.max(1, Math.round(design.test_trials * 1.6 / 60)) +
        ' minutes. You may stop at any time by closing this page; nothing is sent anywhere, ' +
        'the results stay on this computer until you download them.' }),
      el('p', {}, el('label', {}, 'Participant id: ', id)),
      el('p', {}, el('label', {}, agree, ' I have read the above and agree to take part.')),
      problem,
      el('button', { id: 'start', text: 'Continue', onclick: () => {
        const value = id.value.trim();
        if (!/^[A-Za-z0-9_.-]{1,64}$/.test(value)) {
          problem.textContent = 'Please enter a participant id: letters, digits, "-", "_" or "." (at most 64).';
          problem.style.display = '';
        } else if (!agree.checked) {
          problem.textContent = 'Please tick the box to agree before you continue.';
          problem.style.display = '';
        } else {
          session.participant = value;
          calibration(false);
        }
      } }));
    id.focus();
  }

  // A virtual chinrest (after Li, Joo, Yeatman & Reinecke 2020): the participant resizes a
  // card-shaped box to a real credit card held against the screen, which gives CSS pixels per
  // centimetre; with the viewing distance, pixels per degree.
  function calibration(preview) {
    let width = 340;
    const card = el('div', { class: 'card' });
    const slider = el('input', { type: 'range', min: 100, max: 1000, value: width, id: 'card-size' });
    const draw = () => {
      card.style.width = `${width}px`;
      card.style.height = `${width * CARD_ASPECT}px`;
    };
    slider.addEventListener('input', () => { width = Number(slider.value); draw(); });
    draw();
    const d = design.display.viewing_distance_cm;
    show(
      el('h1', { text: 'Screen size' }),
      el('p', { text: 'Hold a credit card (or any card of that size) flat against the screen, over ' +
        'the white box, and move the slider until the box is exactly as wide as the card. ' +
        `Then sit about ${d} cm from the screen (about an arm's length) for the rest of the experiment.` }),
      card, slider,
      el('button', { id: 'calibrated', text: 'The box matches my card', onclick: () => {
        if (preview) return;
        session.pxPerCm = width / CARD_WIDTH_CM;
        // Pixels per degree at distance d: the length that subtends one degree, 2 d tan(0.5 deg).
        session.ppdScreen = session.pxPerCm * 2 * d * Math.tan(0.5 * Math.PI / 180);
        session.calibrated = true;
        practiceIntro();
      } }),
      el('button', { id: 'skip', text: 'Skip (no card)', onclick: () => { if (!preview) practiceIntro(); } }),
      el('p', { class: 'note', text: 'Skipping shows the images at their own size in pixels.' }));
  }

  function practiceIntro() {
    const practice = design.trials.filter((t) => t.block === 'practice');
    const test = design.trials.filter((t) => t.block === 'test');
    const k = design.keys;
    const go = () => run(practice, 'Practice').then(testIntro.bind(null, test));
    show(el('h1', { text: practice.length ? 'Practice' : 'Ready' }),
      el('p', {}, 'Keep your fingers on ', key(k.convex), ' (bump) and ', key(k.concave),
        ' (dimple). Press the space bar to begin.'),
      el('p', { class: 'note', text: 'Loading the images\u2026' }));
    preload().then(() => {
      app.querySelector('.note').textContent = 'Ready.';
      return nextKey([' ']);
    }).then(practice.length ? go : () => testIntro(test, true),
      (e) => fail(`${e.message}: serve this folder from a web server (see README.md)`));
  }

  function testIntro(test, noPractice) {
    show(el('h1', { text: noPractice ? 'Ready' : 'Practice done' }),
      el('p', { text: 'Now the experiment itself. Press the space bar to begin.' }));
    nextKey([' ']).then(() => run(test, 'Trial')).then(() => end());
  }

  // The trial screen's parts: the progress indicator, the stage and the key reminder.
  function trialScreen(label, index, count) {
    const bar = el('div', { class: 'bar' }, el('div', { style: { width: `${100 * index / count}%` } }));
    const progress = el('div', { class: 'progress', id: 'progress' },
      el('div', { text: `${label} ${index + 1} of ${count}` }), bar);
    const stage = el('div', { class: 'stage' });
    const k = design.keys;
    const reminder = el('div', { class: 'reminder' }, key(k.convex), ' bump \u00a0 \u00a0 ',
      key(k.concave), ' dimple');
    app.className = 'screen';
    app.replaceChildren(progress, stage, reminder);
    return stage;
  }

  async function run(trials, label) {
    const keys = [design.keys.convex, design.keys.concave];
    for (let i = 0; i < trials.length; i++) {
      const t = trials[i];
      const stage = trialScreen(label, i, trials.length);
      stage.replaceChildren(el('div', { class: 'fixation', text: '+' }));
      await wait(design.timing.fixation_ms);
      stage.replaceChildren(sized(t.image));
      // The onset is the frame in which the image is first drawn; until that frame comes, the
      // moment it was put on the page (so a page the browser does not draw, such as one in a
      // hidden frame, still runs). The keys count from the insertion on.
      const inserted = performance.now();
      let drawn = null;
      requestAnimationFrame(() => { drawn = performance.now(); });
      const press = await nextKey(keys);
      const onset = drawn !== null && drawn <= press.time ? drawn : inserted;
      record(t, press.key === design.keys.convex ? 'convex' : 'concave',
        Math.round(press.time - onset), press.key);
      stage.replaceChildren();
      await wait(design.timing.blank_ms);
    }
  }

  function end(note) {
    const text = csv(session.rows);
    const name = `shadelab-${session.participant}.csv`;
    const link = el('a', { id: 'download', download: name, text: `Download ${name}`,
      href: URL.createObjectURL(new Blob([text], { type: 'text/csv' })) });
    const info = {
      participant: session.participant,
      calibrated: session.calibrated,
      px_per_cm: session.pxPerCm,
      ppd_screen: session.ppdScreen,
      viewing_distance_cm: design.display.viewing_distance_cm,
      finished: new Date().toISOString(),
      user_agent: navigator.userAgent,
    };
    show(el('h1', { text: 'Thank you!' }),
      el('p', { text: note || 'You have finished. Please download the results and send the file to the experimenter.' }),
      el('p', {}, link),
      el('pre', { id: 'results', text: text }),
      el('p', { class: 'note', text: 'Session (not part of the CSV):' }),
      el('pre', { id: 'session', text: JSON.stringify(info, null, 1) }));
  }

  // Shows a screen as a participant sees it, recording nothing.
  function preview(which) {
    if (which === 'calibration') return calibration(true);
    if (which !== 'trial') return fail(`preview: unknown screen '${which}' (use trial or calibration)`);
    const t = design.trials.find((x) => x.block === 'test');
    preload().then(() => {
      trialScreen('Trial', 0, design.test_trials).replaceChildren(sized(t.image));
    }, (e) => fail(e.message));
  }

  // ---- Start ----------------------------------------------------------------------------

  if (url.has('simulate')) {
    let model;
    try {
      model = parseSimulate(url.get('simulate'));
    } catch (e) {
      fail(e.message);
    }
    if (model) simulate(model);
  } else if (url.has('preview')) {
    preview(url.get('preview'));
  } else {
    instructions();
  }
})();
