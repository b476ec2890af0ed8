// dualarm_qp._kernel's collision scene: the capsules' closed form, coal's pairs with a box
// and the velocity damper's rows (module.cpp makes the module).
#include "binding.hpp"

#include "boxes.hpp"  // IndexVec
#include "clearance.hpp"
#include "coal_pairs.hpp"

namespace dqk_binding {

using namespace nb::literals;

void bind_collision(nb::module_& m) {
  m.def(
      "segment_closest_points",
      [](const CArray& p0_, const CArray& p1_, const CArray& q0_, const CArray& q1_) {
        const PointsMap p0 = points(p0_, "p0"), p1 = points(p1_, "p1"), q0 = points(q0_, "q0"),
                        q1 = points(q1_, "q1");
        const Index k = p0.rows();
        require(p1.rows() == k && q0.rows() == k && q1.rows() == k,
                "segment_closest_points: p0, p1, q0, q1 must be (k, 3) each");
        Vec s(k), t(k);
        dqk::Points x(k, 3), y(k, 3);
        for (Index i = 0; i < k; ++i) {
          const dqk::SegmentPoints c = dqk::closest_points(
              p0.row(i).transpose(), p1.row(i).transpose(), q0.row(i).transpose(),
              q1.row(i).transpose());
          s[i] = c.s;
          t[i] = c.t;
          x.row(i) = c.x.transpose();
          y.row(i) = c.y.transpose();
        }
        return nb::make_tuple(out(std::move(s)), out(std::move(t)), out(std::move(x)),
                              out(std::move(y)));
      },
      "p0"_a, "p1"_a, "q0"_a, "q1"_a,
      "Closest points of k segment pairs: (s, t, x, y).");

  m.def(
      "capsule_proximities",
      [](const CArray& a0_, const CArray& a1_, const Vec& ra, const CArray& b0_,
         const CArray& b1_, const Vec& rb) {
        const PointsMap a0 = points(a0_, "a0"), a1 = points(a1_, "a1"), b0 = points(b0_, "b0"),
                        b1 = points(b1_, "b1");
        const Index k = ra.size();
        require(a0.rows() == k && a1.rows() == k && b0.rows() == k && b1.rows() == k &&
                    rb.size() == k,
                "capsule_proximities: a0, a1, b0, b1 must be (k, 3), ra and rb (k,)");
        Vec d(k);
        dqk::Points pa(k, 3), pb(k, 3), n(k, 3);
        dqk::capsule_proximities(a0, a1, ra, b0, b1, rb, d, pa, pb, n);
        return nb::make_tuple(out(std::move(d)), out(std::move(pa)), out(std::move(pb)),
                              out(std::move(n)));
      },
      "a0"_a, "a1"_a, "ra"_a, "b0"_a, "b1"_a, "rb"_a,
      "Signed distances, witness points and unit normals of k capsule pairs: "
      "(distance, point_a, point_b, normal).");

  nb::class_<dqk::CoalPairs>(
      m, "CoalPairs",
      "The collision scene's bodies as coal geometries, with one coal solver per pair "
      "that has a box (what scene_proximities measures them with).")
      .def(
          "__init__",
          [](dqk::CoalPairs* self, const std::vector<int>& kinds, const CArray& params,
             const CArray& local, const std::vector<int>& ia, const std::vector<int>& ib,
             const std::vector<bool>& boxed, double gjk_tolerance, double epa_tolerance) {
            new (self) dqk::CoalPairs(kinds, points(params, "params"),
                                      c_matrix(local, 4, "local"), ia, ib, boxed,
                                      gjk_tolerance, epa_tolerance);
          },
          "kinds"_a, "params"_a, "local"_a, "ia"_a, "ib"_a, "boxed"_a, "gjk_tolerance"_a,
          "epa_tolerance"_a,
          "Body i: kinds[i] (0 none, 1 box of sizes params[i], 2 capsule of radius and "
          "length params[i, :2] along its z axis, 3 sphere of radius params[i, 0]) posed "
          "by local[4i:4i+4] in its frame; pair k is (ia[k], ib[k]), measured by coal when "
          "boxed[k].")
      .def_prop_ro("n_pairs", &dqk::CoalPairs::n_pairs)
      .def(
          "measure",
          [](const dqk::CoalPairs& self, size_t pair, const CArray& frame_a,
             const CArray& frame_b) {
            const Eigen::Matrix4d T_a = c_matrix(frame_a, 4, "frame_a");
            const Eigen::Matrix4d T_b = c_matrix(frame_b, 4, "frame_b");
            const dqk::CapsuleProximity p = self.measure(pair, T_a, T_b);
            return nb::make_tuple(p.distance, out(Vec(p.point_a)), out(Vec(p.point_b)),
                                  out(Vec(p.normal)));
          },
          "pair"_a, "frame_a"_a, "frame_b"_a,
          "Coal's proximity of pair k, its bodies in the frames (4, 4) frame_a and "
          "frame_b: (distance, point_a, point_b, normal).");

  m.def(
      "scene_proximities",
      [](const CArray& frames, const std::vector<int>& body_frame, const CArray& a_local,
         const CArray& b_local, const Vec& r, const Vec& sphere, const std::vector<int>& ia,
         const std::vector<int>& ib, double within, const dqk::CoalPairs* exact) {
        dqk::Proximities p = dqk::scene_proximities(
            c_matrix(frames, 4, "frames"), body_frame, points(a_local, "a_local"),
            points(b_local, "b_local"), r, sphere, ia, ib, within, exact);
        dqk::IndexVec pairs(static_cast<Index>(p.pairs.size()));
        for (size_t k = 0; k < p.pairs.size(); ++k) pairs[static_cast<Index>(k)] = p.pairs[k];
        return nb::make_tuple(p.finite, out(std::move(pairs)), out(std::move(p.distance)),
                              out(std::move(p.point_a)), out(std::move(p.point_b)),
                              out(std::move(p.normal)));
      },
      "frames"_a, "body_frame"_a, "a_local"_a, "b_local"_a, "r"_a, "sphere"_a, "ia"_a, "ib"_a,
      "within"_a, "exact"_a = nb::none(),
      "The collision scene's proximities of the pairs whose bounding spheres are closer "
      "than within, by their capsules, and by coal for a pair with a box when exact (a "
      "CoalPairs) is given: (finite, pairs, distance, point_a, point_b, normal); finite "
      "is False when a capsule distance is not finite (nothing measured by coal then).");

  nb::class_<dqk::DamperScene>(
      m, "DamperScene",
      "A collision scene's velocity damper (CollisionLimit): rows(...) gives a step's rows.")
      .def(
          "__init__",
          [](dqk::DamperScene* self, const std::vector<int>& body_frame, const CArray& a_local,
             const CArray& b_local, const Vec& r, const Vec& sphere, const std::vector<int>& ia,
             const std::vector<int>& ib, const dqk::CoalPairs* exact,
             const std::vector<int>& owner, const std::vector<int>& model_frame,
             const std::vector<int>& leader_frames, const std::vector<int>& follower_frames,
             double d_i, double d_s, double gain, double zero_row, Index n_l, Index n_f,
             Index grasp_start, Index n) {
            new (self) dqk::DamperScene(
                body_frame, points(a_local, "a_local"), points(b_local, "b_local"), r, sphere,
                ia, ib, exact, owner, model_frame, leader_frames, follower_frames, d_i, d_s,
                gain, zero_row, n_l, n_f, grasp_start, n);
          },
          "body_frame"_a, "a_local"_a, "b_local"_a, "r"_a, "sphere"_a, "ia"_a, "ib"_a,
          "exact"_a.none(), "owner"_a, "model_frame"_a, "leader_frames"_a,
          "follower_frames"_a, "d_i"_a, "d_s"_a, "gain"_a, "zero_row"_a, "n_l"_a, "n_f"_a,
          "grasp_start"_a, "n"_a, nb::keep_alive<1, 9>(),
          "The scene's bodies and pairs (as scene_proximities reads them, exact the scene's "
          "CoalPairs or None), each body's owner and model frame, the arms' link frames, "
          "the damper's distances d_i and d_s [m], its gain [1/s], the zero-row threshold "
          "and the decision vector's layout.")
      .def(
          "rows",
          [](const dqk::DamperScene& self, const dqk::Chain& leader, const dqk::Chain& follower,
             const CArray& J_object, const CArray& T_object) {
            return damper_tuple(self.rows(leader, follower, c_matrix(J_object, -1, "J_object"),
                                          c_matrix(T_object, 4, "T_object")));
          },
          "leader"_a, "follower"_a, "J_object"_a, "T_object"_a,
          "This step's rows: (finite, pairs, G, h); finite is False when the scene's "
          "frames gave a non-finite distance (nothing else is computed then).");

  m.def(
      "damper_rows",
      [](const dqk::Chain& leader, const dqk::Chain& follower, const CArray& J_object,
         const Eigen::Vector3d& object_origin, const std::vector<int>& owners,
         const std::vector<int>& frames, const CArray& point_a, const CArray& point_b,
         const CArray& normal, Index n_l, Index n_f, Index grasp_start, Index n) {
        return out(dqk::damper_rows(leader, follower, c_matrix(J_object, -1, "J_object"),
                                    object_origin, owners, frames, points(point_a, "point_a"),
                                    points(point_b, "point_b"), points(normal, "normal"), n_l,
                                    n_f, grasp_start, n));
      },
      "leader"_a, "follower"_a, "J_object"_a, "object_origin"_a, "owners"_a, "frames"_a,
      "point_a"_a, "point_b"_a, "normal"_a, "n_l"_a, "n_f"_a, "grasp_start"_a, "n"_a,
      "The velocity damper's rows n^T (J_a(p_a) - J_b(p_b)) over the decision vector.");
}

}  // namespace dqk_binding
