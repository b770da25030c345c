// The one entry point of the vendored three.js bundle (see build.sh): the
// library, the orbit controls and the convex-hull geometry (convex shapes),
// exposed as the global `THREE`.
export * from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
export { ConvexGeometry } from 'three/addons/geometries/ConvexGeometry.js';
