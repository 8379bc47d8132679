#version 450
// Writes the texture-space position of the face; alpha 1 marks "a face was drawn here" (the target clears to 0).
layout(location = 0) in vec3 tex_pos;
layout(location = 0) out vec4 position;

void main() {
    position = vec4(tex_pos, 1.0);
}
