!> Prescribed coordinates that turn part of a planar model rigidly: a driven hinge of an open
!> chain or tree. Turning the part beyond such a hinge about the hinge's node leaves every other
!> element's deformation as it is, so the configuration at joint angles p0 + dp and modal
!> coordinates eta is that at (p0, eta) with the parts turned. Every derivative of the nodal
!> coordinates x along such a joint then follows from one of lower order without the model: for
!> a field f = d^k x / dz... (a derivative of x, k >= 1), d f / dp_j is J (f_i - f_c) at the
!> positions of the turned nodes i, c the node turned about, J the quarter turn, and zero at
!> the angles (they turn by the same amount whatever f). The expansion (reduction_expansion)
!> takes its X2 and X3 columns along such joints from these O(n) products instead of element
!> passes and solves.
!>
!> A joint counts as a turn when, at the expansion point, X1's column of its angle is such a
!> motion (angles 0 or 1, positions J (x - c) or 0, one fixed node at c), no element but the
!> joint's own ties a turned coordinate to one that stays, and every element with a turned
!> coordinate keeps its deformation under a finite turn (which excludes elements that see an
!> absolute direction).
module reduction_turns
  use core_kinds, only: wp
  use core_sort, only: sort_by_key
  use model_system, only: model_t, COORD_PHI
  implicit none
  private
  public :: turn_t, find_turns, turn_derivative, turn_order, apply_turns_transposed
  public :: rotation, position_pairs, CHECK_ANGLE

  !> Relative tolerance of the tests on X1's entries (they come from solves: round-off about
  !> 1e-14 of their size).
  real(wp), parameter :: TURN_TOL = 1.0e-8_wp
  !> Angle of the finite turn the elements' deformations are checked under [rad].
  real(wp), parameter :: CHECK_ANGLE = 0.3_wp

  !> A prescribed coordinate that turns part of the model about one of its nodes.
  type :: turn_t
    integer :: centre(2) = 0                 !< x and y coordinates of the node turned about
    integer, allocatable :: moving(:, :)     !< (2, :) x and y coordinates of the turned nodes
    integer, allocatable :: angles(:)        !< angle coordinates that turn with them
  end type turn_t

  integer, parameter :: STAYS = 0, TURNS = 1, CENTRE = 2

contains

  !> turns(j) for every prescribed coordinate j (the first columns of x1 = DF T at x0), and
  !> whether all of them are turns; .false. for a spatial model or one without prescribed
  !> coordinates.
  subroutine find_turns(model, x0, x1, turns, all_turn)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x0(:), x1(:, :)
    type(turn_t), allocatable, intent(out) :: turns(:)
    logical, intent(out) :: all_turn
    integer :: j
    allocate(turns(model%n_rh))
    all_turn = model%dim == 2 .and. model%n_rh > 0
    do j = 1, model%n_rh
      if (.not. all_turn) exit
      call find_turn(model, x0, x1(:, j), j, turns(j), all_turn)
    end do
  end subroutine find_turns

  !> df = d f / dp along the turn, for a field f of the series (see the module).
  pure subroutine turn_derivative(turn, f, df)
    type(turn_t), intent(in) :: turn
    real(wp), intent(in) :: f(:)
    real(wp), intent(out) :: df(:)
    integer :: i
    df = 0.0_wp
    associate (cx => f(turn%centre(1)), cy => f(turn%centre(2)))
      do i = 1, size(turn%moving, 2)
        df(turn%moving(1, i)) = cy - f(turn%moving(2, i))
        df(turn%moving(2, i)) = f(turn%moving(1, i)) - cx
      end do
    end associate
  end subroutine turn_derivative

  !> The turns deepest first (a turn's part lies inside its parent's, so it has fewer nodes):
  !> turning them in this order, each about its centre's current place, carries every part
  !> with its parents.
  pure function turn_order(turns) result(order)
    type(turn_t), intent(in) :: turns(:)
    integer :: order(size(turns))
    integer :: j
    order = [(j, j = 1, size(turns))]
    call sort_by_key(order, [(size(turns(j)%moving, 2), j = 1, size(turns))])
  end function turn_order

  !> f <- L^T f for the turns' linear map L on fields (reduction_frames' turn): the
  !> generalised forces of nodal loads f at the turned configuration, on the fields of the
  !> unturned one.
  pure subroutine apply_turns_transposed(turns, order, delta, f)
    type(turn_t), intent(in) :: turns(:)
    integer, intent(in) :: order(:)
    real(wp), intent(in) :: delta(:)
    real(wp), intent(inout) :: f(:)
    real(wp) :: co, si, bx, by, mx, my
    integer :: o, j, i, ix, iy
    ! L = T_1 ... T_n with T_1 the last turn applied: L^T applies the transposes first to last.
    do o = size(order), 1, -1
      j = order(o)
      if (delta(j) == 0) cycle
      co = cos(delta(j))
      si = sin(delta(j))
      mx = 0.0_wp
      my = 0.0_wp
      do i = 1, size(turns(j)%moving, 2)
        ix = turns(j)%moving(1, i)
        iy = turns(j)%moving(2, i)
        bx = co * f(ix) + si * f(iy)
        by = -si * f(ix) + co * f(iy)
        mx = mx + f(ix) - bx
        my = my + f(iy) - by
        f(ix) = bx
        f(iy) = by
      end do
      f(turns(j)%centre(1)) = f(turns(j)%centre(1)) + mx
      f(turns(j)%centre(2)) = f(turns(j)%centre(2)) + my
    end do
  end subroutine apply_turns_transposed

  !> The rotation by angle a.
  pure function rotation(a) result(r)
    real(wp), intent(in) :: a
    real(wp) :: r(2, 2)
    r = reshape([cos(a), sin(a), -sin(a), cos(a)], [2, 2])
  end function rotation

  !> Whether prescribed coordinate j (X1 column d) is a turn, and which.
  subroutine find_turn(model, x0, d, j, turn, ok)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x0(:), d(:)
    integer, intent(in) :: j
    type(turn_t), intent(out) :: turn
    logical, intent(out) :: ok
    integer :: state(size(d)), i, n_moving, n_centre, own
    integer, allocatable :: pairs(:, :)
    logical :: covered(size(d))
    real(wp) :: length, c(2), ci(2)
    ok = .false.
    if (model%q_mode(j) == 0) return
    own = model%modes(model%q_mode(j))%element
    length = max(1.0e-3_wp, maxval(abs(x0)))
    state = STAYS
    covered = .false.
    ! Angles turn by the joint's angle (X1 = 1) or stay.
    do i = 1, size(d)
      if (model%coord_kind(i) /= COORD_PHI) cycle
      covered(i) = .true.
      if (abs(d(i) - 1) <= TURN_TOL) then
        state(i) = TURNS
      else if (abs(d(i)) > TURN_TOL) then
        return
      end if
    end do
    ! Positions move as J (x - c) about one point c, or stay.
    pairs = position_pairs(model)
    n_moving = 0
    c = 0.0_wp
    do i = 1, size(pairs, 2)
      associate (ix => pairs(1, i), iy => pairs(2, i))
        covered([ix, iy]) = .true.
        if (norm2(d([ix, iy])) <= TURN_TOL * length) cycle
        ci = [x0(ix) - d(iy), x0(iy) + d(ix)]
        if (n_moving > 0 .and. norm2(ci - c) > TURN_TOL * length) return
        if (n_moving == 0) c = ci
        n_moving = n_moving + 1
        state([ix, iy]) = TURNS
      end associate
    end do
    ! A coordinate of no node that moves cannot be turned (one that stays has zero
    ! derivatives along the turn, as the turn's product gives).
    if (n_moving == 0 .or. any(.not. covered .and. abs(d) > TURN_TOL * length)) return
    ! Exactly one node that stays sits at c: the joint's.
    n_centre = 0
    do i = 1, size(pairs, 2)
      if (state(pairs(1, i)) /= STAYS) cycle
      if (norm2(x0(pairs(:, i)) - c) > TURN_TOL * length) cycle
      n_centre = n_centre + 1
      turn%centre = pairs(:, i)
    end do
    if (n_centre /= 1) return
    state(turn%centre) = CENTRE
    if (.not. elements_allow(model, x0, pairs, state, own, c)) return
    turn%moving = pairs(:, pack([(i, i = 1, size(pairs, 2))], state(pairs(1, :)) == TURNS))
    turn%angles = pack([(i, i = 1, size(d))], state == TURNS .and. model%coord_kind == COORD_PHI)
    ok = .true.
  end subroutine find_turn

  !> No element but the joint's own (own) ties a turned coordinate to one that stays, and every
  !> element with a turned coordinate keeps its deformation under a finite turn about c.
  function elements_allow(model, x0, pairs, state, own, c) result(allow)
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: x0(:), c(2)
    integer, intent(in) :: pairs(:, :), state(:), own
    logical :: allow
    real(wp) :: x_turned(size(x0)), xe(model%max_dofs), e(model%max_modes), et(model%max_modes)
    real(wp) :: de(model%max_modes, model%max_dofs), rot(2, 2)
    integer :: iel, nd, nm, k, i
    allow = .false.
    rot = rotation(CHECK_ANGLE)
    x_turned = x0
    where (state == TURNS .and. model%coord_kind == COORD_PHI) x_turned = x0 + CHECK_ANGLE
    do i = 1, size(pairs, 2)
      if (state(pairs(1, i)) /= TURNS) cycle
      x_turned(pairs(:, i)) = c + matmul(rot, x0(pairs(:, i)) - c)
    end do
    do iel = 1, model%n_elements
      if (iel == own) cycle
      associate (el => model%elements(iel)%e)
        nd = size(el%dofs)
        if (.not. any(state(el%dofs) == TURNS)) cycle
        if (any(state(el%dofs) == STAYS)) return
        nm = el%n_modes()
        do k = 1, nd
          xe(k) = x0(el%dofs(k))
        end do
        call el%evaluate(xe(1:nd), e(1:nm), de(1:nm, 1:nd))
        do k = 1, nd
          xe(k) = x_turned(el%dofs(k))
        end do
        call el%evaluate(xe(1:nd), et(1:nm), de(1:nm, 1:nd))
        if (any(abs(et(1:nm) - e(1:nm)) > TURN_TOL * (1 + abs(e(1:nm))))) return
      end associate
    end do
    allow = .true.
  end function elements_allow

  !> The x and y coordinates (2, :) of the nodes that have both.
  pure function position_pairs(model) result(pairs)
    type(model_t), intent(in) :: model
    integer, allocatable :: pairs(:, :)
    logical :: both(size(model%node_coord, 2))
    both = model%node_coord(1, :) > 0 .and. model%node_coord(2, :) > 0
    pairs = reshape(pack(model%node_coord(1:2, :), spread(both, 1, 2)), [2, count(both)])
  end function position_pairs
end module reduction_turns
