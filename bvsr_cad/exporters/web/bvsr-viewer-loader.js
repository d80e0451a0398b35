/* The report's 3D view, loaded from a file:// page with nothing fetched from a network. Chromium refuses
   module scripts and fetch() of file:// URLs, but runs classic scripts and inline modules: three.js's
   modules come as data: URLs in an import map, the viewer as an inline module, each scene's GLB
   (gzipped, base64) as a classic script calling BVSRViewer.addScene. three.js: MIT licence, __LICENSE__. */
(function () {
  "use strict";
  var V = window.BVSRViewer = window.BVSRViewer || {};
  var data = {}, waiting = {};
  V.addScene = function (name, gzipBase64) {
    data[name] = gzipBase64;
    if (waiting[name]) waiting[name](gzipBase64);
  };
  /* A promise of the scene's data, its script added to the page the first time. */
  V.scene = function (entry) {
    if (data[entry.name]) return Promise.resolve(data[entry.name]);
    return new Promise(function (resolve, reject) {
      waiting[entry.name] = resolve;
      var tag = document.createElement("script");
      tag.src = entry.file;
      tag.onerror = function () { reject(new Error("could not load " + entry.file)); };
      document.head.appendChild(tag);
    });
  };
  V.start = function (opts) {
    V.opts = opts;
    if (V.run) V.run(opts);
  };
  var map = document.createElement("script");
  map.type = "importmap";
  map.textContent = JSON.stringify({imports: __IMPORTS__});
  document.head.appendChild(map);
  var app = document.createElement("script");
  app.type = "module";
  app.textContent = __APP__;
  document.head.appendChild(app);
})();
