// Triangle meshes from files through Assimp (Debian libassimp-dev): OBJ, PLY (ASCII and
// binary), STL, glTF, ... Every mesh of the file is merged, polygons are triangulated and node
// transforms applied; points and lines are ignored.
#include "bsdfkit/render/render.h"

#ifdef BSDFKIT_HAVE_ASSIMP
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#endif

namespace bsdfkit::render {

std::string load_mesh(const std::string &path, std::vector<Float> *vertices, std::vector<uint32_t> *indices) {
#ifdef BSDFKIT_HAVE_ASSIMP
    Assimp::Importer importer;
    const aiScene *sc = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                    aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!sc) return path + ": " + importer.GetErrorString();
    vertices->clear();
    indices->clear();
    for (unsigned mi = 0; mi < sc->mNumMeshes; ++mi) {
        const aiMesh *m = sc->mMeshes[mi];
        if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        uint64_t base = vertices->size() / 3;
        if (base + m->mNumVertices > uint64_t(UINT32_MAX)) return path + ": too many vertices";
        for (unsigned v = 0; v < m->mNumVertices; ++v) {
            vertices->push_back(m->mVertices[v].x);
            vertices->push_back(m->mVertices[v].y);
            vertices->push_back(m->mVertices[v].z);
        }
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const aiFace &face = m->mFaces[f];
            if (face.mNumIndices != 3) continue;
            for (int k = 0; k < 3; ++k) indices->push_back(uint32_t(base + face.mIndices[k]));
        }
    }
    if (indices->empty()) return path + ": the file holds no triangles";
    return "";
#else
    (void)vertices;
    (void)indices;
    return path + ": bsdfkit was built without Assimp (install libassimp-dev and rebuild)";
#endif
}

} // namespace bsdfkit::render
