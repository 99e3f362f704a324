// fathom's scene page: the parts of three.js it uses, bundled into one IIFE
// (window.FATHOM_THREE) by assets/three/bundle.sh; three.js is MIT (LICENSE here).
export {
  WebGLRenderer, Scene, PerspectiveCamera, Color, BufferGeometry, BufferAttribute,
  Mesh, MeshLambertMaterial, LineBasicMaterial, Line, LineSegments, Points,
  PointsMaterial, AmbientLight, DirectionalLight, Group, SphereGeometry,
  MeshBasicMaterial, Vector3, GridHelper, DoubleSide, Raycaster,
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
