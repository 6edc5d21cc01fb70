/**
 * The protocol, from the generated TypeScript client (clients/generated/typescript, made from spec/ by
 * `pltf stubs`): telegram classes, enums and the codec. Only its sans-IO modules are imported (its Client
 * needs Node's sockets); nothing of the layouts is written a second time here.
 */
export * from "@pltf/wire";
export * from "@pltf/protocol";
export * from "@pltf/codec";
