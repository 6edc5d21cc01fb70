// vite's `?raw` imports: a file's text (the tests read fixtures this way; no Node types needed).
declare module "*?raw" {
  const text: string;
  export default text;
}
