// The parts of three.js the exported HTML viewer uses, bundled into one classic script
// (window.BPTHREE) so a single self-contained HTML file can inline it.
import {
  AmbientLight, Box3, Color, DirectionalLight, HemisphereLight, MeshBasicMaterial, PerspectiveCamera,
  Raycaster, Scene,
  SRGBColorSpace, Vector2, Vector3, WebGLRenderer,
} from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

window.BPTHREE = {
  AmbientLight, Box3, Color, DirectionalLight, HemisphereLight, MeshBasicMaterial, PerspectiveCamera,
  Raycaster, Scene,
  SRGBColorSpace, Vector2, Vector3, WebGLRenderer, GLTFLoader, OrbitControls,
};
