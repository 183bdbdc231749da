// shadelab experiment: the study around the trials (shadelab-timeline.js), run by jsPsych 8.
//
//   browser check (refuses phones and touch-only tablets) -> welcome and consent -> fullscreen
//   -> screen calibration (jsPsych's virtual chinrest: a credit card gives pixels per cm; with the
//   viewing distance, pixels per degree) -> instructions, practice, test with breaks -> saving
//
// The design is embedded in index.html (as in design.json). Data are jsPsych's own (CSV or JSON,
// one row per screen), every row with the participant's id, order seed, Prolific ids, the
// design's hash, ppd and how it was measured, the viewing distance, the user agent and the
// screen and window size; see shadelab-timeline.js for the trial rows.
//
// Where the data go, in this order:
//   - under JATOS (jatos.html, which loads JATOS's jatos.js): jatos.submitResultData(JSON),
//     then jatos.endStudy (or endStudyAndRedirect to the completion URL);
//   - with a save URL (the URL parameter save_url=URL, else the design's save_url): an HTTP POST
//     of the data (JSON, application/json; or CSV, text/csv, with save_format=csv or the
//     design's save_format), tried 3 times; if it fails, the participant is told so and offered
//     the file to download;
//   - else the participant downloads the CSV.
// Then, when the data were saved and the design has a completion URL (Prolific's, with its
// code), the page goes there.
//
// URL parameters:
//   participant=ID            the participant's id (else PROLIFIC_PID, else one drawn here);
//                             the trial order is drawn from it
//   PROLIFIC_PID, STUDY_ID, SESSION_ID   Prolific's ids, saved in every row
//   save_url=URL, save_format=json|csv   see above
//   calibration=none          no card calibration (one image pixel per CSS pixel)
//   fullscreen=0              do not ask for fullscreen
//   simulate=tilt:T,kappa:K,convex:C,lapse:L,seed:S
//                             pilot mode: jsPsych's simulation mode answers every trial from
//                             the observer model (tilt and kappa required; convex 0.5, lapse 0
//                             and seed 1 by default); the other parameters still apply
//   simulate_mode=visual      the pilot shown screen by screen instead of at once
//   preview=trial             the design's first test trial as a participant sees it (nothing is
//                             recorded or saved), to check the display
(function () {
  'use strict';

  const design = JSON.parse(document.getElementById('design').textContent);
  const DEG = Math.PI / 180;

  function escape(text) {
    return String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
  }

  // A problem the page cannot go on from (bad URL parameters): said on the page.
  function fail(text) {
    document.body.innerHTML = '<main class="shadelab-end"><h1>This page cannot start</h1>' +
      `<div id="message" class="message">${escape(text)}</div></main>`;
  }

  function wait(ms) {
    return new Promise((resolve) => setTimeout(resolve, ms));
  }

  // POSTs `body` to `url`, 3 tries (1 s, then 2 s apart); resolves with '' or the last error.
  async function post(url, body, type) {
    let problem = '';
    for (let attempt = 1; attempt <= 3; attempt++) {
      try {
        const response = await fetch(url, { method: 'POST', headers: { 'Content-Type': type }, body: body });
        if (response.ok) return '';
        problem = `the server answered ${response.status} ${response.statusText}`;
      } catch (e) {
        problem = `the server could not be reached (${e.message})`;
      }
      if (attempt < 3) await wait(1000 * attempt);
    }
    return problem;
  }

  // The end screen: what happened to the data, the file to download, the data themselves.
  function endScreen(participant) {
    const main = document.createElement('main');
    main.className = 'shadelab-end';
    main.innerHTML = '<h1>Thank you!</h1><p id="save-status">Saving your responses\u2026</p>' +
      '<p id="download-line" style="display:none"><a id="download">Download</a></p>' +
      '<p id="completion-line" style="display:none"><a id="completion">Back to the study site</a></p>' +
      '<pre id="results"></pre>';
    document.body.replaceChildren(main);
    return {
      status: (text) => { main.querySelector('#save-status').textContent = text; },
      offer: (csv) => {
        const name = `shadelab-${participant}.csv`;
        const a = main.querySelector('#download');
        a.download = name;
        a.textContent = `Download ${name}`;
        a.href = URL.createObjectURL(new Blob([csv], { type: 'text/csv' }));
        main.querySelector('#download-line').style.display = '';
      },
      completion: (url) => {
        main.querySelector('#completion').href = url;
        main.querySelector('#completion-line').style.display = '';
      },
      results: (csv) => { main.querySelector('#results').textContent = csv; },
    };
  }

  function start(params) {
    const get = (k) => (params[k] === undefined || params[k] === null ? '' : String(params[k]));
    let model = null;
    if (get('simulate')) {
      try {
        model = shadelabTimeline.parseSimulate(get('simulate'));
      } catch (e) {
        fail(e.message);
        return;
      }
    }
    const saveFormat = get('save_format') || design.save_format || 'json';
    if (saveFormat !== 'json' && saveFormat !== 'csv') {
      fail(`save_format '${saveFormat}' must be json or csv`);
      return;
    }
    const participant = get('participant') || get('PROLIFIC_PID') ||
      (model ? `simulated-seed${model.seed}` : shadelabTimeline.participantId({}));
    if (!/^[A-Za-z0-9_.@-]{1,128}$/.test(participant)) {
      fail('participant: use letters, digits, "-", "_", "." or "@" (at most 128)');
      return;
    }
    if (get('preview')) {
      if (get('preview') !== 'trial') {
        fail(`preview: unknown screen '${get('preview')}' (use trial)`);
        return;
      }
      const first = design.trials.find((t) => t.block === 'test');
      const one = Object.assign({}, design, { trials: [first] });
      initJsPsych().run([shadelabTimeline(one, {
        participant: 'preview', params: params, instructions: false, practice: false,
        ppd: design.display.ppd, ppdMethod: 'none: one image pixel per CSS pixel',
      })]);
      return;
    }
    const saveUrl = get('save_url') || design.save_url || '';
    const d = design.display.viewing_distance_cm;
    const session = {
      ppd: design.display.ppd,
      method: model ? 'none (simulated): one image pixel per CSS pixel' : 'none: one image pixel per CSS pixel',
    };

    const jsPsych = initJsPsych({
      show_progress_bar: true,
      auto_update_progress_bar: false,
      message_progress_bar: 'Progress',
      on_finish: () => finish(jsPsych, participant, saveUrl, saveFormat),
    });
    // The timeline puts the participant and the session's columns on every row.
    const trials = shadelabTimeline(design, {
      participant: participant,
      params: params,
      jsPsych: jsPsych,
      ppd: () => session.ppd,
      ppdMethod: () => session.method,
      simulate: model,
    });
    jsPsych.data.addProperties({ ppd: session.ppd, ppd_method: session.method });

    const timeline = [{
      type: jsPsychBrowserCheck,
      features: ['width', 'height', 'browser', 'browser_version', 'mobile', 'os'],
      inclusion_function: (data) => !data.mobile &&
        !(window.matchMedia && window.matchMedia('(any-pointer: coarse)').matches &&
          !window.matchMedia('(any-pointer: fine)').matches),
      exclusion_message: () => '<p>This study needs a computer with a keyboard; it cannot run ' +
        'on a phone or a tablet. Please open the link on a computer.</p>',
      data: { shadelab: 'browser-check' },
    }, {
      type: jsPsychHtmlButtonResponse,
      stimulus: '<div class="shadelab-text"><h1>Bump or dimple?</h1>' +
        '<p>In this study you judge the shape of shaded discs, pressing one of two keys on each ' +
        `trial. It takes about ${Math.max(1, Math.round(design.test_trials * 1.6 / 60))} minutes. ` +
        'You may stop at any time by closing this page; your responses are saved only at the end.</p>' +
        '<p>Do you agree to take part?</p></div>',
      choices: ['I agree'],
      data: { shadelab: 'consent' },
    }];
    if (get('fullscreen') !== '0') {
      timeline.push({
        type: jsPsychFullscreen,
        fullscreen_mode: true,
        message: '<p>The study runs in fullscreen mode.</p>',
        data: { shadelab: 'fullscreen' },
      });
    }
    if (get('calibration') !== 'none' && !model) {
      timeline.push({
        type: jsPsychVirtualChinrest,
        blindspot_reps: 0,
        resize_units: 'none',
        item_path: null,
        viewing_distance_report: 'none',
        adjustment_prompt: '<div class="shadelab-text"><p>Hold a credit card (or any card of that ' +
          'size) flat against the screen and drag the lower right corner of the box until it ' +
          `matches the card. Then sit about ${d} cm from the screen (about an arm's length) for ` +
          'the rest of the study.</p></div>',
        data: { shadelab: 'calibration' },
        on_finish: (data) => {
          // Pixels per degree at distance d: the card's pixels per cm times the length that
          // subtends one degree, 2 d tan(0.5 deg). From the card's own width in pixels and mm:
          // the plugin's px2mm is rounded to two decimals (up to 0.13 % of ppd at 96 dpi).
          const perCm = data.item_width_px / (data.item_width_mm / 10);
          session.ppd = perCm * 2 * d * Math.tan(0.5 * DEG);
          session.method = 'virtual-chinrest card';
          jsPsych.data.addProperties({ ppd: session.ppd, ppd_method: session.method });
        },
      });
    }
    timeline.push(trials);
    if (get('fullscreen') !== '0') {
      timeline.push({ type: jsPsychFullscreen, fullscreen_mode: false, data: { shadelab: 'fullscreen' } });
    }
    if (model) {
      jsPsych.simulate(timeline, get('simulate_mode') === 'visual' ? 'visual' : 'data-only');
    } else {
      jsPsych.run(timeline);
    }
  }

  async function finish(jsPsych, participant, saveUrl, saveFormat) {
    jsPsych.data.addProperties({ window_width: window.innerWidth, window_height: window.innerHeight });
    const data = jsPsych.data.get();
    const csv = data.csv();
    const json = data.json();
    const end = endScreen(participant);
    end.results(csv);
    const completion = design.completion_url || '';
    let saved = false;
    if (typeof jatos !== 'undefined') {
      try {
        await jatos.submitResultData(json);
        saved = true;
        end.status('Your responses were saved. Thank you!');
      } catch (e) {
        end.status(`Your responses could not be saved (${e && e.message ? e.message : e}). ` +
          'Please download the file below and send it to the experimenter.');
        end.offer(csv);
        return;
      }
      if (completion && typeof jatos.endStudyAndRedirect === 'function') {
        jatos.endStudyAndRedirect(completion, true, 'shadelab study completed');
      } else {
        jatos.endStudy(true, 'shadelab study completed');
      }
      return;
    }
    if (saveUrl) {
      const problem = saveFormat === 'csv'
        ? await post(saveUrl, csv, 'text/csv')
        : await post(saveUrl, json, 'application/json');
      if (problem) {
        end.status(`Your responses could not be sent: ${problem}. Please download the file ` +
          'below and send it to the experimenter; nothing is lost.');
        end.offer(csv);
      } else {
        saved = true;
        end.status('Your responses were saved. Thank you!');
      }
    } else {
      end.status('You have finished. Please download the results and send the file to the experimenter.');
      end.offer(csv);
    }
    if (completion) {
      end.completion(completion);
      if (saved) {
        await wait(1500);
        window.location.assign(completion);
      }
    }
  }

  // Under JATOS its own parameters, with the study link's query; else the page's URL.
  if (typeof jatos !== 'undefined') {
    jatos.onLoad(() => start(Object.assign({}, jatos.urlQueryParameters || {})));
  } else {
    start(Object.fromEntries(new URLSearchParams(window.location.search)));
  }
})();
