/**
 * One history interface for both editors (guide 5.4 "Undo", "Redo"; 5.5 the roadmap's toolbar "looks similar"):
 * the document shell (shell.ts) and the Undo/Redo buttons see only this. Two implementations keep their own way
 * of storing a step: the map's `History` (commands.ts) keeps each command's changed objects, so a step on a map of
 * 50,000 objects touches only its objects; the roadmap's `RoadmapHistory` (roadmapdoc.ts) keeps whole copies of a
 * document of a few hundred stations, so an edit is any function of the document.
 */
export interface EditHistory {
  /** Take back the last action; its label, or null when there was nothing to undo. */
  undo(): string | null;
  /** Do again the last action undone; its label, or null when there was nothing to redo. */
  redo(): string | null;
  readonly canUndo: boolean;
  readonly canRedo: boolean;
  /** The label of the last action done (the one Undo takes back); null when there is nothing to undo. */
  readonly label: string | null;
  /** Mark the document saved (or sent): `dirty` is false until the next change, undo or redo. */
  markSaved(): void;
  readonly dirty: boolean;
}
