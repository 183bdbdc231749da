// shadelab-timeline.js: "bump or dimple?" trials as a jsPsych 8 timeline, to run alone (see
// experiment.js, the study `shadelab experiment` writes) or inside a lab's own jsPsych study.
//
//   const timeline = shadelabTimeline(design, { participant: 'P01', jsPsych: jsPsych });
//   jsPsych.run([consent, timeline, questionnaire]);
//
// `design` is the experiment's design.json (fetch it, or paste it into the page). The timeline
// needs jsPsych 8 and three of its plugins loaded as scripts: @jspsych/plugin-preload,
// @jspsych/plugin-html-keyboard-response and @jspsych/plugin-image-keyboard-response (the
// folder's package.json pins their versions).
//
// Options (all optional):
//   participant        the participant's id; by default the URL's `participant`, else
//                      `PROLIFIC_PID`, else one drawn at random (shadelabTimeline.participantId)
//   jsPsych            the jsPsych instance: with it the progress bar follows the test trials
//   imagePath          a prefix for the design's image paths (e.g. 'shadelab/' when the images
//                      lie in a subfolder of the lab's study); default ''
//   ppd                CSS pixels per degree on this display (a number, or a function asked at
//                      each trial, e.g. after a calibration); without it the images' own ppd
//                      is assumed (one image pixel per CSS pixel): the console says so and
//                      every row's ppd_method is 'assumed' (docs/experiments.md shows the
//                      card calibration to add)
//   ppdMethod          how ppd was measured (a string, or a function), saved in every row
//                      (default 'given' when ppd is given)
//   params             the URL parameters to read PROLIFIC_PID, STUDY_ID and SESSION_ID from
//                      (an object or URLSearchParams; default the page's own URL's)
//   participantOnAllRows  with jsPsych given, put the participant and the session's columns
//                      on every row of the study, the lab's own too (true; false: only on
//                      shadelab's rows)
//   instructions       show the task's instructions and the "practice done" screen (true)
//   practice           run the design's practice trials (true)
//   breakEvery         a break after every N test trials (default the design's break_every;
//                      0: none)
//   counterbalanceKeys swap the two keys for half of the participants, by their order seed
//                      (default the design's counterbalance_keys)
//   simulate           an observer model {tilt, kappa, convex, lapse, seed} whose answers the
//                      trials carry as jsPsych simulation options (run with jsPsych.simulate)
//
// The order: the design's practice and test trials, each block shuffled with a seed made of the
// design's seed and the participant id (FNV-1a), so two participants get two orders and the
// same participant the same one. Every trial's data row carries (besides jsPsych's own
// `response` and `rt`): shadelab = 'trial', block, practice, shadelab_trial (1, 2, ... in the
// order shown), rotation_deg, image, key_convex, key_concave, judgement (convex | concave),
// participant, order_seed, design_hash, stimulus, ppd, ppd_method, fullscreen, window_width and
// window_height; and, as every row shadelab makes, the session's columns (sessionColumns):
// prolific_pid, study_id, session_id, shadelab_version, viewing_distance_cm, user_agent,
// screen_width, screen_height and simulated (the observer model, or '' for a person).
// Fixation and break screens carry shadelab = 'fixation' | 'break' (and break = true); other
// rows are the lab's.
(function (global) {
  'use strict';

  // FNV-1a (32 bits) of the UTF-8 bytes of `text`: the participant's order seed.
  function fnv1a(text) {
    let h = 0x811c9dc5;
    for (const b of new TextEncoder().encode(text)) {
      h ^= b;
      h = Math.imul(h, 0x01000193) >>> 0;
    }
    return h >>> 0;
  }

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

  // Fisher-Yates, in place.
  function shuffle(items, random) {
    for (let i = items.length - 1; i > 0; i--) {
      const j = Math.floor(random() * (i + 1));
      [items[i], items[j]] = [items[j], items[i]];
    }
    return items;
  }

  // P(convex | theta) = lapse/2 + (1 - lapse) * pi*vM(theta; mu, kappa) /
  //                     (pi*vM(theta; mu, kappa) + (1 - pi)*vM(theta + 180; mu, kappa)),
  // theta and mu in degrees, tilt convention (0 = up, +90 = left). The von Mises normaliser
  // cancels: the log odds are logit(pi) + 2 kappa cos(theta - mu). Computed step for step as
  // shadelab's ModelParams::p_convex (src/analysis/observer_model.rs), so that
  // `shadelab experiment pilot` draws the same answers as this page.
  function pConvex(theta, m) {
    const x = Math.log(m.convex / (1 - m.convex)) +
      2 * m.kappa * Math.cos((theta - m.tilt) * (Math.PI / 180));
    const p = x >= 0 ? 1 / (1 + Math.exp(-x)) : Math.exp(x) / (1 + Math.exp(x));
    return m.lapse === 0 ? p : 0.5 * m.lapse + (1 - m.lapse) * p;
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

  // The observer model as text, `tilt:T,kappa:K,convex:C,lapse:L,seed:S`: the `simulated`
  // column of its rows ('' for a person).
  function simulateText(m) {
    return m ? `tilt:${m.tilt},kappa:${m.kappa},convex:${m.convex},lapse:${m.lapse},seed:${m.seed}` : '';
  }

  // The columns every row of a session carries besides the participant: Prolific's ids from
  // the URL parameters `params`, the version, the viewing distance, the browser and screen, and
  // whether the answers are simulated.
  function sessionColumns(design, params, model) {
    const p = params || new URLSearchParams(global.location ? global.location.search : '');
    const get = (k) => {
      const v = typeof p.get === 'function' ? p.get(k) : p[k];
      return v === undefined || v === null ? '' : String(v);
    };
    return {
      prolific_pid: get('PROLIFIC_PID'),
      study_id: get('STUDY_ID'),
      session_id: get('SESSION_ID'),
      shadelab_version: design.version,
      viewing_distance_cm: design.display.viewing_distance_cm,
      user_agent: global.navigator ? global.navigator.userAgent : '',
      screen_width: global.screen ? global.screen.width : '',
      screen_height: global.screen ? global.screen.height : '',
      simulated: simulateText(model),
    };
  }

  // The participant's id: `participant`, else Prolific's `PROLIFIC_PID`, else one drawn here.
  function participantId(params) {
    const p = params || new URLSearchParams(global.location ? global.location.search : '');
    const get = (k) => (typeof p.get === 'function' ? p.get(k) : p[k]);
    const given = get('participant') || get('PROLIFIC_PID');
    if (given) return String(given);
    const bytes = new Uint8Array(6);
    global.crypto.getRandomValues(bytes);
    return 'anon-' + Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
  }

  function kbd(k) {
    return `<kbd>${k === ' ' ? 'space' : String(k).toUpperCase()}</kbd>`;
  }

  function shadelabTimeline(design, options) {
    const calibrated = !!options && options.ppd !== undefined && options.ppd !== null;
    const o = Object.assign({
      participant: null,
      jsPsych: null,
      imagePath: '',
      params: null,
      participantOnAllRows: true,
      instructions: true,
      practice: true,
      breakEvery: design.break_every || 0,
      counterbalanceKeys: !!design.counterbalance_keys,
      simulate: null,
    }, options || {});
    if (!calibrated) {
      o.ppd = design.display.ppd;
      o.ppdMethod = 'assumed';
      if (global.console) {
        global.console.warn(`shadelab: no calibration, so ${design.display.ppd} pixels per ` +
          'degree are assumed (one image pixel per CSS pixel) and every row\'s ppd_method is ' +
          '\'assumed\'; give shadelabTimeline a ppd, e.g. from a card calibration (docs/experiments.md)');
      }
    } else if (o.ppdMethod === undefined || o.ppdMethod === null) {
      o.ppdMethod = 'given';
    }
    const participant = o.participant || participantId(o.params);
    const orderSeed = fnv1a(`${design.seed}:${participant}`);
    // Who, in which design, and the session: on every row shadelab makes (and, with jsPsych
    // and participantOnAllRows, on the lab's rows too).
    const columns = Object.assign({
      participant: participant,
      order_seed: orderSeed,
      // design_hash: design.design_hash tells these rows from an earlier design's.
      design_hash: design.design_hash,
    }, sessionColumns(design, o.params, o.simulate));
    const tag = (data) => Object.assign({}, columns, data);
    if (o.jsPsych && o.participantOnAllRows) o.jsPsych.data.addProperties(columns);
    const random = mulberry32(orderSeed);
    let keys = { convex: design.keys.convex, concave: design.keys.concave };
    if (o.counterbalanceKeys && (orderSeed & 1) === 1) {
      keys = { convex: keys.concave, concave: keys.convex };
    }
    const value = (v) => (typeof v === 'function' ? v() : v);
    const practice = o.practice ? shuffle(design.trials.filter((t) => t.block === 'practice'), random) : [];
    const test = shuffle(design.trials.filter((t) => t.block === 'test'), random);
    // The simulated observer's answers are drawn from their own stream, in the order shown.
    const answers = o.simulate ? mulberry32(o.simulate.seed) : null;
    const [h, w] = design.display.visual_size;
    const reminder = `<p class="shadelab-reminder">${kbd(keys.convex)} bump &nbsp; &nbsp; ${kbd(keys.concave)} dimple</p>`;
    let shown = 0;
    // jsPsych has a progress bar only when initJsPsych was given show_progress_bar.
    const progress = (p) => {
      if (o.jsPsych && o.jsPsych.progressBar) o.jsPsych.progressBar.progress = p;
    };

    function trial(t, index, count) {
      const fixation = {
        type: jsPsychHtmlKeyboardResponse,
        stimulus: '<div class="shadelab-fixation">+</div>',
        choices: 'NO_KEYS',
        trial_duration: design.timing.fixation_ms,
        data: tag({ shadelab: 'fixation' }),
      };
      const image = {
        type: jsPsychImageKeyboardResponse,
        stimulus: o.imagePath + t.image,
        choices: [keys.convex, keys.concave],
        stimulus_width: () => Math.round(w * value(o.ppd)),
        stimulus_height: () => Math.round(h * value(o.ppd)),
        maintain_aspect_ratio: false,
        render_on_canvas: false,
        prompt: reminder,
        post_trial_gap: design.timing.blank_ms,
        data: tag({
          shadelab: 'trial',
          block: t.block,
          practice: t.block === 'practice',
          break: false,
          rotation_deg: t.rotation_deg,
          image: t.image,
          key_convex: keys.convex,
          key_concave: keys.concave,
          stimulus_name: design.stimulus,
        }),
        on_start: () => { if (t.block === 'test') progress(index / count); },
        on_finish: (data) => {
          shown += 1;
          data.shadelab_trial = shown;
          data.judgement = data.response === keys.convex ? 'convex'
            : (data.response === keys.concave ? 'concave' : '');
          data.ppd = value(o.ppd);
          data.ppd_method = value(o.ppdMethod);
          data.fullscreen = !!(global.document && global.document.fullscreenElement);
          data.window_width = global.innerWidth;
          data.window_height = global.innerHeight;
          if (t.block === 'test') progress((index + 1) / count);
        },
      };
      if (answers) {
        const convex = answers() < pConvex(t.rotation_deg, o.simulate);
        image.simulation_options = {
          data: { response: convex ? keys.convex : keys.concave, rt: Math.round(400 + 400 * answers()) },
        };
      }
      return [fixation, image];
    }

    function screen(html, extra) {
      return Object.assign({
        type: jsPsychHtmlKeyboardResponse,
        stimulus: `<div class="shadelab-text">${html}</div>`,
        choices: [' '],
      }, extra || {}, { data: tag((extra && extra.data) || { shadelab: 'instructions' }) });
    }

    const timeline = [{
      type: jsPsychPreload,
      images: design.images.map((i) => o.imagePath + i.file),
      message: 'Loading the images\u2026',
      error_message: 'The images could not be loaded: serve this folder from a web server (see README.md).',
      data: tag({ shadelab: 'preload' }),
    }];
    if (o.instructions) {
      timeline.push(screen(
        '<h2>Bump or dimple?</h2>' +
        '<p>You will see a shaded disc in the middle of the screen. It can look like a bump ' +
        '(bulging towards you) or like a dimple (a hollow). There are no right or wrong ' +
        'answers: we want to know how it looks to you.</p>' +
        `<p>Look at the cross in the middle; when the disc appears, press ${kbd(keys.convex)} ` +
        `if it looks like a bump or ${kbd(keys.concave)} if it looks like a dimple. Answer ` +
        'quickly, by your first impression.</p>' +
        `<p>${practice.length ? `First ${practice.length} practice trials, then ` : ''}` +
        `${test.length} trials.</p><p>Press the space bar to begin.</p>`));
    }
    practice.forEach((t, i) => timeline.push(...trial(t, i, practice.length)));
    if (o.instructions && practice.length) {
      timeline.push(screen('<h2>Practice done</h2><p>Now the experiment itself. ' +
        `Keep your fingers on ${kbd(keys.convex)} (bump) and ${kbd(keys.concave)} (dimple).</p>` +
        '<p>Press the space bar to begin.</p>'));
    }
    test.forEach((t, i) => {
      timeline.push(...trial(t, i, test.length));
      if (o.breakEvery > 0 && (i + 1) % o.breakEvery === 0 && i + 1 < test.length) {
        timeline.push(screen('<h2>A short break</h2>' +
          `<p>You have done ${i + 1} of ${test.length} trials.</p>` +
          '<p>Rest your eyes; press the space bar when you are ready to go on.</p>',
        { data: { shadelab: 'break', break: true } }));
      }
    });
    // Who and in what order, for the study around it (not enumerable: jsPsych would pass a
    // timeline node's own properties on to its trials as parameters).
    const node = { timeline: timeline };
    Object.defineProperty(node, 'shadelab', {
      value: { participant: participant, order_seed: orderSeed, keys: keys, columns: columns },
      enumerable: false,
    });
    return node;
  }

  shadelabTimeline.participantId = participantId;
  shadelabTimeline.parseSimulate = parseSimulate;
  shadelabTimeline.sessionColumns = sessionColumns;
  shadelabTimeline.orderSeed = (design, participant) => fnv1a(`${design.seed}:${participant}`);
  global.shadelabTimeline = shadelabTimeline;
})(typeof window !== 'undefined' ? window : globalThis);
