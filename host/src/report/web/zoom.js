// The report's zoom page (PAGE_files/zoom.html): the result's full-size
// pictures from their Deep Zoom pyramids in OpenSeadragon, one at a time.
// The pyramids are given inline (no .dzi is fetched: a page opened from file:
// may not read files), the tiles drawn on a 2D canvas (images from file: are
// not WebGL textures). Test hook: window.lightstageZoom.
(function () {
  const sources = JSON.parse(document.getElementById('lightstage-zoom-sources').textContent);
  const names = Object.keys(sources);
  const tileSource = (pyramid) => ({
    Image: {
      xmlns: 'http://schemas.microsoft.com/deepzoom/2008',
      Url: pyramid.tiles,
      Format: pyramid.format,
      Overlap: String(pyramid.overlap),
      TileSize: String(pyramid.tile_size),
      Size: { Width: String(pyramid.width), Height: String(pyramid.height) },
    },
  });
  const state = { shown: null, tilesLoaded: 0, tilesFailed: 0 };
  const viewer = OpenSeadragon({
    id: 'zoom',
    drawer: 'canvas',
    showNavigationControl: false,
    maxZoomPixelRatio: 4,
    visibilityRatio: 0.5,
  });
  viewer.addHandler('tile-loaded', () => state.tilesLoaded++);
  viewer.addHandler('tile-load-failed', () => state.tilesFailed++);

  const buttons = document.getElementById('pictures');
  function show(name) {
    return new Promise((resolve, reject) => {
      viewer.addOnceHandler('open', () => resolve(name));
      viewer.addOnceHandler('open-failed', (event) => reject(new Error(event.message)));
      viewer.open(tileSource(sources[name]));
      state.shown = name;
      for (const button of buttons.querySelectorAll('button'))
        button.setAttribute('aria-pressed', String(button.dataset.name === name));
      document.getElementById('caption').textContent = sources[name].caption;
    });
  }
  for (const name of names) {
    const button = document.createElement('button');
    button.type = 'button';
    button.dataset.name = name;
    button.textContent = sources[name].label;
    button.addEventListener('click', () => show(name));
    buttons.appendChild(button);
  }
  window.lightstageZoom = { viewer, state, show, ready: show(names[0]) };
})();
