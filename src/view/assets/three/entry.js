// The one entry point of the vendored three.js bundle (see build.sh): the
// library and the orbit controls, exposed as the global `THREE`.
export * from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
